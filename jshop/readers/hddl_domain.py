"""Turn an HDDL model (:mod:`htn.jshop.readers.hddl`) into the planner's syntax objects.

How HDDL's semantics (Höller et al., AAAI 2020) map onto JSHOP2's:

* **Types** become unary type predicates named ``type:t`` (a name no HDDL
  predicate can have, so that a predicate may share its name with a type, as
  Barman's ``ingredient`` does): an object ``o - t`` is the atom
  ``(type:t o)`` of the initial state, every supertype is implied
  (``Domain.implied``; ``object`` is the root of every type), and the
  domain's constants are ``Domain.facts``.
* An **action** ``a`` becomes the operator ``!a``: its typed parameters become
  type conditions after its precondition; ``forall`` and ``when`` effects
  become conditional delete/add items evaluated in the state before the action
  (``Operator.effects_in_prestate``, PDDL's semantics); ``(increase
  (total-cost) n)`` is its cost (default 1).
* A **method** becomes a one-branch JSHOP2 method of its task, the branch
  labelled with the method's name. In HDDL every method parameter is bound to
  an object of its type before the subtasks are instantiated, so its
  precondition is the conjunction of the written precondition, the
  ``:constraints``, the type conditions of the parameters and the conditions
  pulled up from its subtasks (:mod:`htn.jshop.readers.pullup`), in an order that
  binds variables early and tests a literal as soon as its variables are bound
  (:func:`~htn.jshop.readers.hddl_formulas.order_conjuncts`; a negation,
  disjunction, ``forall`` or equality needs its variables bound to mean what
  PDDL says). JSHOP2's if-then-else
  between branches does not arise: HDDL methods are independent alternatives.
* Subtasks keep HDDL's partial order (:mod:`htn.jshop.readers.hddl_order`):
  ``:ordered-subtasks`` and chains of ``:ordering`` make an ordered task
  list, ``:subtasks`` with no ``:ordering`` an unordered one, and any other
  ``:ordering`` a list with a :class:`~htn.jshop.language.syntax.PartialOrder`.
  Pulled-up conditions (:mod:`htn.jshop.readers.pullup`) are tested when a
  method is applied, which is only sound when nothing can interleave with
  its subtasks: a domain with any method that is not totally ordered, or a
  problem whose initial task network is not, is read without them
  (:func:`for_problem`).
* The **problem**'s objects become type atoms, its initial task network the
  task list, its goal ``ProblemInstance.goal`` (checked on the final state).

Every error names ``file:line:col``.
"""

from __future__ import annotations

from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError
from htn.jshop.language.terms import Var, variables

from .hddl_checks import check_domain, check_method, type_ancestors, unique_labels, unique_params
from .hddl_formulas import Formulas, Scope, order_conjuncts, type_condition, type_predicate
from .hddl_model import (
    TOP,
    TOP_METHOD,
    ActionDef,
    EffectCost,
    EffectForall,
    EffectWhen,
    Exists,
    HDomain,
    HProblem,
    MethodDef,
    Subtask,
)
from .hddl_order import is_total, subtask_order
from .pullup import pulled_conditions

# ------------------------------------------------------------------ domain


class _Domain:
    def __init__(self, h: HDomain, ancestors: dict):
        self.h = h
        self.ancestors = ancestors
        self.method_count = 0

    def check_types(self, params) -> None:
        for p in params:
            for t in p.types:
                if t not in self.ancestors:
                    raise HtnError.at(p.type_pos or p.pos, f"unknown type {t}")

    def declare(self, scope: Scope, params, what: str) -> dict:
        self.check_types(params)
        unique_params(params, what)
        names = {}
        for p in params:
            names[p.name] = p.name
            scope.var(p.name)
        return names

    # ------------------------------------------------------------ actions
    def operator(self, a: ActionDef) -> S.Operator:
        scope = Scope()
        names = self.declare(scope, a.params, f"action {a.name}")
        f = Formulas(scope, self.h.predicates)
        params = [scope.var(p.name) for p in a.params]
        f.outer.update(v.index for v in params)
        conds, types = f.conjuncts(a.pre, names)
        types += [
            type_condition(v, p.types, p.pos)
            for v, p in zip(params, a.params)
            if p.types != ("object",)
        ]
        pre = order_conjuncts(conds, types, {v.index for v in params}, f.outer)
        dels, adds, cost, conditional = _Effects(f).convert(a.effect, names)
        head = S.TaskAtom("!" + a.name, tuple(params), False, a.pos)
        return S.Operator(
            head,
            S.Precondition(_and(pre), pos=a.pos),
            S.Effects(dels),
            S.Effects(adds),
            cost,
            nvars=scope.size,
            pos=a.pos,
            effects_in_prestate=conditional,
        )

    # ------------------------------------------------------------ methods
    def task_name(self, st) -> str:
        """A subtask's task: ``!name`` for an action (its arity and the
        method's were checked when the domain was read, :mod:`.hddl_checks`)."""
        return "!" + st.name if st.name in self.h.actions else st.name

    def method(self, m: MethodDef, pulled: list) -> S.Method:
        scope = Scope()
        names = self.declare(
            scope,
            m.params,
            f"method {m.name}" if m.name != TOP_METHOD else "the initial task network",
        )
        f = Formulas(scope, self.h.predicates)
        params = [scope.var(p.name) for p in m.params]
        f.outer.update(v.index for v in params)
        head = tuple(f.term(x, names, m.task.pos) for x in m.task.args)
        conds, types = f.conjuncts(m.pre, names)
        more, more_types = f.conjuncts(m.network.constraints, names)
        pulled_up = [f.expr(e, names) for e in pulled]
        conds += more + pulled_up
        types += more_types + [type_condition(v, p.types, p.pos) for v, p in zip(params, m.params)]
        bound = {v.index for v in variables(head, [])}
        pre = order_conjuncts(conds, types, bound, f.outer)
        subtasks, order = subtask_order(m.network, f"method {m.name}", m.pos)
        items = [
            S.TaskAtom(
                self.task_name(st), tuple(f.term(x, names, st.pos) for x in st.args), False, st.pos
            )
            for st in subtasks
        ]
        branch = S.Branch(
            m.name,
            S.Precondition(_and(pre), pos=m.pos, pulled=tuple(pulled_up)),
            _task_list(items, order, m.network.pos),
            m.pos,
        )
        method = S.Method(
            S.TaskAtom(m.task.name, head, False, m.task.pos),
            [branch],
            nvars=scope.size,
            index=self.method_count,
            pos=m.pos,
        )
        self.method_count += 1
        return method


class _Effects:
    """Flattens an action's effect into delete and add lists."""

    def __init__(self, formulas: Formulas):
        self.f = formulas

    def convert(self, effect, names: dict):
        self.dels: list = []
        self.adds: list = []
        self.cost: object = 1.0  # a number or a term
        self.conditional = False
        self.groups: dict = {}
        self._walk(effect, names, [], [])
        return self.dels, self.adds, self.cost, self.conditional

    def _walk(self, e, names, vs, conds) -> None:
        if isinstance(e, list):
            for x in e:
                self._walk(x, names, vs, conds)
        elif isinstance(e, EffectCost):
            self.cost = e.amount
        elif isinstance(e, EffectForall):
            new_vs, types, inner = self.f.quantify(e.vars, names, e.pos)
            self._walk(e.effect, inner, vs + new_vs, conds + types)
        elif isinstance(e, EffectWhen):
            cond = self.f.expr(e.cond, names)
            self._walk(e.effect, names, vs, conds + [cond])
        else:
            negative = isinstance(e, S.Not)
            atom = self.f.atom(e.expr if negative else e, names)
            target = self.dels if negative else self.adds
            if not vs and not conds:
                target.append(atom)
                return
            self.conditional = True
            key = (id(conds[-1]) if conds else None, tuple(v.index for v in vs), negative)
            group = self.groups.get(key)
            if group is None:
                group = self.groups[key] = S.EffectForAll(vs, _and(conds), [], atom.pos)
                target.append(group)
            group.atoms.append(atom)


def _task_list(items: list, order, pos) -> S.TaskList:
    if order is True or order is False:
        return S.TaskList(items, order, pos)
    return S.TaskList(items, False, pos, order=order)


def _and(items: list):
    return items[0] if len(items) == 1 else S.And(items)


def domain_from_model(h: HDomain, pullup: bool | None = None) -> S.Domain:
    """The syntax objects of an HDDL domain (see the module docstring);
    ``pullup`` None: pull conditions up when every method is totally ordered."""
    if pullup is None:
        pullup = all(is_total(m.network) for m in h.methods)
    t = _Domain(h, check_domain(h))
    for c in h.constants:
        t.check_types([c])
    for task in h.tasks.values():
        t.check_types(task.params)
        if task.name in h.actions:
            raise HtnError.at(task.pos, f"{task.name} is both a task and an action")
    d = S.Domain(h.name, file=h.file, pos=h.pos, language="hddl", spelling=h.spelling)
    for a in h.actions.values():
        d.operators["!" + a.name] = [t.operator(a)]
    pulled = pulled_conditions(h, t.ancestors) if pullup else {}
    d.hddl = h
    d.pullup = pullup
    for m in h.methods:
        d.methods.setdefault(m.task.name, []).append(t.method(m, pulled.get(id(m), [])))
    for c in h.constants:
        if len(c.types) != 1:
            raise HtnError.at(c.pos, f"constant {c.name} must have one type, not (either ...)")
    d.facts = [S.Atom(type_predicate(c.types[0]), (c.name,), c.pos) for c in h.constants]
    d.implied = {
        type_predicate(ty): [type_predicate(a) for a in anc]
        for ty, anc in t.ancestors.items()
        if anc
    }
    return d


def top_method(domain: S.Domain, top: MethodDef) -> S.Method:
    """The method of the artificial root task that binds the parameters of an
    initial task network (``ProblemInstance.top``), with its pulled-up
    conditions, in the domain's terms."""
    if domain.hddl is None:
        raise HtnError.at(top.pos, "an HDDL problem with parameters needs an HDDL domain")
    t = _Domain(domain.hddl, type_ancestors(domain.hddl))
    check_method(domain.hddl, top)
    pulled = {}
    if domain.pullup:
        pulled = pulled_conditions(domain.hddl, t.ancestors, extra=[top])
    return t.method(top, pulled.get(id(top), []))


def attach_roots(domain: S.Domain, problem: S.Problem) -> None:
    """Give each instance of ``problem`` whose initial task network has
    parameters its root method (``ProblemInstance.root``), in the terms of
    ``domain``, the domain it is planned with: built once, here."""
    for inst in problem.instances:
        if inst.top is not None and inst.root is None:
            inst.root = top_method(domain, inst.top)


def for_problem(domain: S.Domain, problem: S.Problem) -> S.Domain:
    """The domain to plan ``problem`` with: read again without pulled-up
    conditions when the problem's initial task network is not totally
    ordered (its tasks interleave with every method's subtasks)."""
    if (
        domain.hddl is None
        or not domain.pullup
        or all(inst.tasks.ordered for inst in problem.instances)
    ):
        return domain
    again = domain_from_model(domain.hddl, pullup=False)
    again.sha256 = domain.sha256  # the same file
    return again


# ------------------------------------------------------------------ problem


def problem_from_model(h: HProblem) -> S.Problem:
    """The syntax objects of an HDDL problem (see the module docstring)."""
    state = []
    for o in h.objects:
        if len(o.types) != 1:
            raise HtnError.at(o.pos, f"object {o.name} must have one type, not (either ...)")
        state.append(S.Atom(type_predicate(o.types[0]), (o.name,), o.pos))
    for a in h.init:
        if any(isinstance(x, Var) for x in a.args):
            raise HtnError.at(a.pos, "atoms in the initial state must be ground")
        state.append(a)
    declared = {p.name for p in h.params}
    items = []
    unique_labels(h.network, "the initial task network")
    subtasks, order = subtask_order(h.network, "the initial task network", h.pos)
    for st in subtasks:
        for x in st.args:
            if isinstance(x, Var) and x.name not in declared:
                raise HtnError.at(
                    st.pos, f"variable {x.name} is not a parameter of the initial task network"
                )
        items.append(S.TaskAtom(st.name, st.args, False, st.pos))
    top = None
    if h.params or _has_constraints(h.network):
        # the network's :constraints are a precondition of its artificial
        # root method, like its parameters' types
        assert h.network is not None  # parameters come with the :htn network
        top = MethodDef(TOP_METHOD, h.params, Subtask(None, TOP, (), h.pos), None, h.network, h.pos)
    goal, nvars = None, 0
    if h.goal is not None:
        scope = Scope()
        f = Formulas(scope)
        goal = S.Precondition(f.expr(h.goal, {}), pos=getattr(h.goal, "pos", None))
        nvars = scope.size
    pos = h.network.pos if h.network is not None else h.pos
    instance = S.ProblemInstance(
        state, _task_list(items, order, pos), h.pos, goal=goal, goal_nvars=nvars, top=top
    )
    return S.Problem(
        h.name,
        h.domain_name,
        [instance],
        file=h.file,
        pos=h.pos,
        language="hddl",
        spelling=h.spelling,
        hddl=h,
    )


def _has_constraints(net) -> bool:
    c = net.constraints if net is not None else None
    return c is not None and not (isinstance(c, S.And) and not c.items)


def resolve_problem_tasks(domain: S.Domain, problem: S.Problem) -> None:
    """An HDDL initial task network may name actions as well as compound
    tasks (Höller et al. 2020, the problem's task network is any task
    network); the problem file alone cannot tell which, so once the domain
    is known an action's name becomes its operator ``!name``. A network with
    a root method (``top``) is resolved by that method already."""
    h = domain.hddl
    if h is None or problem.language != "hddl":
        return
    for inst in problem.instances:
        for t in S.task_atoms(inst.tasks):
            if t.name in h.actions and t.name not in h.tasks:
                t.name = "!" + t.name


def check_problem_symbols(domain: S.Domain, problem: S.Problem) -> None:
    """Every atom of an HDDL problem's initial state and goal names a
    predicate of its domain, with as many arguments as it declares, and
    only objects of the problem or constants of the domain: a goal that
    could never hold is an input error, not a search to the time limit."""
    h, hp = domain.hddl, problem.hddl
    if h is None or hp is None:
        return
    objects = {o.name for o in hp.objects} | {c.name for c in h.constants}

    def atom(a: S.Atom, where: str) -> None:
        params = h.predicates.get(a.pred)
        if params is None:
            raise HtnError.at(
                a.pos,
                f"unknown predicate {a.pred} in the {where} (the domain "
                "declares no such predicate)",
            )
        if len(params) != len(a.args):
            raise HtnError.at(
                a.pos,
                f"predicate {a.pred} takes {len(params)} argument(s), "
                f"given {len(a.args)} in the {where}",
            )
        terms(a.args, a.pos, where)

    def terms(args, pos, where: str) -> None:
        for x in args:
            if not isinstance(x, Var) and x not in objects:
                raise HtnError.at(
                    pos,
                    f"unknown object {x} in the {where} (neither an "
                    "object of the problem nor a constant of the domain)",
                )

    def formula(e) -> None:
        if isinstance(e, S.Atom):
            atom(e, "goal")
        elif isinstance(e, (S.And, S.Or)):
            for x in e.items:
                formula(x)
        elif isinstance(e, S.Not):
            formula(e.expr)
        elif isinstance(e, S.Equal):
            terms((e.left, e.right), e.pos, "goal")
        elif isinstance(e, Exists):
            formula(e.expr)
        elif isinstance(e, S.ForAll):
            formula(e.cond)
            formula(e.then)

    for a in hp.init:
        atom(a, "initial state")
    formula(hp.goal)


def from_model(h):
    """The syntax objects of an HDDL domain or problem model."""
    return domain_from_model(h) if isinstance(h, HDomain) else problem_from_model(h)
