"""A UP hierarchical problem as the planner's model, built in memory.

The UP problem (``unified_planning.model.htn.HierarchicalProblem``) is turned
into the HDDL model that :mod:`htn.jshop.readers.hddl` reads from text
(:class:`~htn.jshop.readers.hddl_model.HDomain`,
:class:`~htn.jshop.readers.hddl_model.HProblem`), and that into the planner's
syntax objects by :mod:`htn.jshop.readers.hddl_domain`, so a problem has the
same meaning whether it comes from UP or from an HDDL file: user types become
type predicates, an action ``a`` the operator ``!a``, a method a one-branch
method of its task whose branch is labelled with the method's name (its
precondition joined by its static constraints, its parameters' types and
the conditions pulled up from its subtasks), an initial task network with
variables the method of an artificial root task. Names are UP's, unchanged,
so a plan maps back to UP's actions, methods and objects
(:mod:`htn.up.decompose`).

Subtasks are taken in their total order (``TaskNetwork.total_order()``); a
partial order is passed on as HDDL's ``:ordering`` (see :mod:`htn.up.kind`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError
from htn.jshop.language.terms import Var
from htn.jshop.readers.hddl_domain import attach_roots, domain_from_model, problem_from_model
from htn.jshop.readers.hddl_model import (
    ActionDef,
    EffectCost,
    HDomain,
    HProblem,
    MethodDef,
    Network,
    Param,
    Subtask,
    TaskDef,
)
from htn.jshop.readers.hddl_order import linearise

from .formulas import Expressions, Unsupported, param, var_name
from .kind import TASK_ORDERS


@dataclass
class Conversion:
    """The planner's model of one UP problem, and how its parts correspond."""

    problem: Any  # the UP HierarchicalProblem
    domain: S.Domain
    instance: S.ProblemInstance
    # the initial task network's UP subtasks in the order the planner does them
    network_order: list = field(default_factory=list)
    # UP method name -> its UP subtasks in that order
    method_order: dict = field(default_factory=dict)
    # UP method name -> the planner's method (its one branch has that label)
    methods: dict = field(default_factory=dict)
    warnings: list = field(default_factory=list)


def convert(problem) -> Conversion:
    """The planner's domain and problem instance for a UP hierarchical problem.

    Raises :class:`~htn.up.formulas.Unsupported` for what htn cannot express
    and :class:`~htn.jshop.language.errors.HtnError` for what the HDDL
    conversion refuses (both are one-line messages)."""
    from unified_planning.model.htn import HierarchicalProblem

    if not isinstance(problem, HierarchicalProblem):
        raise Unsupported(
            f"htn solves hierarchical problems (HierarchicalProblem), not {type(problem).__name__}"
        )
    _check_problem(problem)
    warnings: list = []
    h = HDomain(problem.name or "unified-planning", file="")
    for t in problem.user_types:
        h.types[t.name] = [t.father.name] if t.father is not None else []
    object_fluents = {}
    for f in problem.fluents:
        params = [param(p, f"parameter {p.name} of fluent {f.name}") for p in f.signature]
        if f.type.is_user_type():
            object_fluents[f.name] = f.type.name
            params.append(Param("?value", (f.type.name,)))
        elif not f.type.is_bool_type():
            raise Unsupported(
                f"fluent {f.name} is of type {f.type}; htn supports boolean and object fluents"
            )
        h.predicates[f.name] = params
    x = Expressions(object_fluents)
    costs = _costs(problem, warnings)
    for a in problem.actions:
        _check_action(a)
        effect = x.effects(a) + [EffectCost(costs.get(a.name, 1.0))]
        h.actions[a.name] = ActionDef(
            a.name, [param(p) for p in a.parameters], _conjunction(x, a.preconditions), effect
        )
    for t in problem.tasks:
        h.tasks[t.name] = TaskDef(t.name, [param(p) for p in t.parameters])
    orders = {}
    for m in problem.methods:
        net, orders[m.name] = _network(x, m, f"method {m.name}")
        achieved = m.achieved_task
        task = Subtask(
            None, achieved.task.name, tuple(Var(var_name(p.name)) for p in achieved.parameters)
        )
        h.methods.append(
            MethodDef(
                m.name,
                [param(p) for p in m.parameters],
                task,
                _conjunction(x, m.preconditions),
                net,
            )
        )
    domain = domain_from_model(h)
    net, order = _network(x, problem.task_network, "the initial task network")
    hp = HProblem(
        problem.name or "problem",
        h.name,
        file="",
        objects=[Param(o.name, (o.type.name,)) for o in problem.all_objects],
        params=[param(v, f"variable {v.name}") for v in problem.task_network.variables],
        network=net,
        init=_initial_state(problem),
        goal=_conjunction(x, problem.goals),
    )
    read = problem_from_model(hp)
    instance = read.instances[0]
    # problem_from_model leaves the names of the network's subtasks as written,
    # without the "!" of an action's operator (it does not see the domain)
    for t in instance.tasks.items:
        if isinstance(t, S.TaskAtom) and t.name in h.actions:  # a flat list of atoms
            t.name = "!" + t.name
    attach_roots(domain, read)
    methods = {m.branches[0].label: m for ms in domain.methods.values() for m in ms}
    return Conversion(problem, domain, instance, order, orders, methods, warnings)


def _check_problem(problem) -> None:
    """Refuse what the rest of the conversion would not notice."""
    for what, items in (
        ("timed effects", problem.timed_effects),
        ("timed goals", problem.timed_goals),
        ("trajectory constraints", problem.trajectory_constraints),
        ("state invariants", problem.state_invariants),
    ):
        if items:
            raise Unsupported(f"the problem has {what}")
    defaults = problem.fluents_defaults
    explicit: dict = {}
    for fe in problem.explicit_initial_values:
        explicit[fe.fluent().name] = explicit.get(fe.fluent().name, 0) + 1
    for f in problem.fluents:
        if f not in defaults:
            groundings = 1
            for p in f.signature:
                groundings *= len(list(problem.objects(p.type))) if p.type.is_user_type() else 0
            if explicit.get(f.name, 0) < groundings:
                raise Unsupported(
                    f"fluent {f.name} has no initial value for some arguments (and no default)"
                )


def _check_action(a) -> None:
    from unified_planning.model import InstantaneousAction

    if not isinstance(a, InstantaneousAction):
        raise Unsupported(
            f"action {a.name} is a {type(a).__name__}; htn supports instantaneous actions"
        )
    if a.simulated_effect is not None:
        raise Unsupported(f"action {a.name} has a simulated effect")


def _conjunction(x: Expressions, exprs):
    """The HDDL formula of a list of conditions (None when there is none)."""
    items = [x.formula(e) for e in exprs]
    if not items:
        return None
    return items[0] if len(items) == 1 else S.And(items)


def _network(x: Expressions, tn, owner: str) -> tuple[Network, list]:
    """The HDDL task network of a UP method or initial task network, and its
    UP subtasks in the planner's order."""
    by_id = {st.identifier: st for st in tn.subtasks}
    subs = {
        i: Subtask(i, st.task.name, tuple(x.term(a) for a in st.parameters))
        for i, st in by_id.items()
    }
    total = tn.total_order()
    if total is not None:
        net = Network([subs[i] for i in total], ordered=True)
    else:
        precedences = tn.partial_order()
        if precedences is None:
            raise Unsupported(f"{owner} has temporal constraints; htn orders subtasks only")
        if "TASK_ORDER_PARTIAL" not in TASK_ORDERS:
            raise Unsupported(
                f"{owner} orders its subtasks partially; htn plans with totally ordered subtasks"
            )
        net = Network(
            list(subs.values()), ordered=False, ordering=[(a, b, None) for a, b in precedences]
        )
    net.constraints = _conjunction(x, tn.non_temporal_constraints())
    return net, [by_id[s.label] for s in linearise(net, owner, None)]


def _costs(problem, warnings: list) -> dict:
    """Action name -> cost (a number), from the problem's quality metric."""
    out: dict = {}
    for metric in problem.quality_metrics:
        if metric.is_minimize_sequential_plan_length():
            continue  # every cost 1, the planner's default
        if not metric.is_minimize_action_costs():
            raise Unsupported(
                f"the quality metric {metric} is not supported; htn minimises "
                "action costs or plan length"
            )
        unset = []
        for a in problem.actions:
            cost = metric.get_action_cost(a)
            if cost is None:
                unset.append(a.name)
                continue
            if not (cost.is_int_constant() or cost.is_real_constant()):
                raise Unsupported(
                    f"the cost of action {a.name} is {cost}; htn supports constant costs"
                )
            out[a.name] = float(cost.constant_value())
        if unset:
            warnings.append(f"no cost is set for {', '.join(unset)}: cost 1 each")
    return out


def _initial_state(problem) -> list:
    """The true atoms of the initial state (closed world: what is not listed
    is false); an object fluent's value is its atom's last argument."""
    defaults = problem.fluents_defaults
    implicit = any(
        not (v.is_bool_constant() and not v.bool_constant_value()) for v in defaults.values()
    )
    # the implicit values are needed only when some default is not false
    values = problem.initial_values if implicit else problem.explicit_initial_values
    atoms = []
    for fe, v in values.items():
        f = fe.fluent()
        args = tuple(a.object().name for a in fe.args)
        if f.type.is_bool_type():
            if v.bool_constant_value():
                atoms.append(S.Atom(f.name, args))
        else:
            atoms.append(S.Atom(f.name, args + (v.object().name,)))
    return atoms


def checked(problem) -> Conversion:
    """:func:`convert`, with every refusal as :class:`Unsupported`."""
    try:
        return convert(problem)
    except HtnError as e:
        raise Unsupported(str(e)) from None
