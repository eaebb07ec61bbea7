"""Validation of a UP ``HierarchicalPlan`` against its hierarchical problem.

A hierarchical plan is valid (total-order HTN semantics, Höller et al.,
AAAI 2020) when

1. its action sequence is executable from the initial state and reaches the
   goal: this is ``htn validate`` (:func:`htn.jshop.checks.validate.validate_plan`),
   which replays the plan as the planner would (manual 5.2.1);
2. its decomposition accounts for that sequence: every subtask of the initial
   task network is achieved by an instance of its action or decomposed by a
   method of its task, whose arguments are the subtask's, and recursively for
   the method's subtasks, so that the actions met in order (the subtasks'
   total order) are exactly the plan's; the variables of the initial task
   network get one value each, which satisfies its constraints;
3. every method's precondition (with its static constraints and its
   parameters' types) holds under its parameters in the state where it is
   applied: the state before its first action, as the planner applies it.

:func:`check` says which of these fails first, in one line.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from htn.jshop.checks.validate import Unpriced, check_steps, validate_plan
from htn.jshop.language.terms import Var
from htn.jshop.plans.plan import Step

from .convert import Conversion


@dataclass
class Check:
    """The outcome of checking one hierarchical plan."""

    valid: bool
    message: str = ""
    failed_action: Any | None = None  # the UP action instance that cannot be applied
    goal_failed: bool = False


class Invalid(Exception):
    """A decomposition that does not account for the plan; the message says where."""


def check(conv: Conversion, plan) -> Check:
    """Validate a UP ``HierarchicalPlan`` (see the module docstring)."""
    actions = list(plan.action_plan.actions)
    steps = [
        Step("!" + a.action.name, tuple(_name(x) for x in a.actual_parameters)) for a in actions
    ]
    check_steps(conv.domain, steps, "")
    verdict = validate_plan(conv.domain, conv.instance, Unpriced(steps))
    if not verdict.valid:
        k = verdict.failed_step
        if k is not None and k < len(actions):
            return Check(False, f"action {k + 1}: {verdict.reason}", failed_action=actions[k])
        return Check(False, verdict.reason, goal_failed=True)
    try:
        _Walk(conv, actions).run(plan.decomposition)
    except Invalid as e:
        return Check(False, str(e))
    return Check(True)


def _name(e) -> str:
    if not e.is_object_exp():
        raise Invalid(f"{e} is not an object")
    return e.object().name


class _Walk:
    """Walks a decomposition in execution order, replaying the actions."""

    def __init__(self, conv: Conversion, actions: list):
        from htn.jshop.search.planner import Planner

        self.conv = conv
        self.actions = actions
        self.next = 0
        self.replay = Planner.for_state(conv.domain, conv.instance.state)
        self.compiled: dict = {}

    def run(self, decomposition) -> None:
        order = self.conv.network_order
        _same_ids(decomposition, order, "the initial task network")
        binding = self._network_variables(decomposition, order)
        if self.conv.instance.top is not None:
            self._top(binding)
        self._walk(decomposition, order, binding)
        if self.next != len(self.actions):
            raise Invalid(
                f"the decomposition accounts for {self.next} of the plan's "
                f"{len(self.actions)} actions"
            )

    # ------------------------------------------------------------ the initial network
    def _network_variables(self, decomposition, order) -> dict:
        """The value of each variable of the initial task network, from the
        arguments of what achieves the subtasks that mention it."""
        binding: dict = {}
        for st in order:
            actual = self._arguments(decomposition.subtasks[st.identifier])
            for arg, value in zip(st.parameters, actual):
                if arg.is_parameter_exp():
                    name = arg.parameter().name
                    if binding.setdefault(name, value) != value:
                        raise Invalid(
                            f"variable {name} of the initial task network is both "
                            f"{binding[name]} and {value}"
                        )
        return binding

    def _top(self, binding: dict) -> None:
        m = self.conv.instance.root
        names = [v.name for v in self.conv.problem.task_network.variables]
        unset = [n for n in names if n not in binding]
        if unset:
            raise Invalid(
                f"no subtask gives variable(s) {', '.join(unset)} of the initial "
                "task network a value"
            )
        if not self._holds(m, [binding.get(n) for n in names]):
            raise Invalid(
                "the values of the initial task network's variables ("
                + ", ".join(f"{n} = {binding.get(n)}" for n in names)
                + ") do not satisfy its constraints"
            )

    # ------------------------------------------------------------ the walk
    def _walk(self, decomposition, order, env: dict) -> None:
        from unified_planning.plans.hierarchical_plan import MethodInstance

        work = [(iter(order), decomposition, env)]
        while work:
            it, dec, env = work[-1]
            st = next(it, None)
            if st is None:
                work.pop()
                continue
            impl = dec.subtasks[st.identifier]
            wanted = tuple(
                env[a.parameter().name] if a.is_parameter_exp() else _name(a) for a in st.parameters
            )
            if isinstance(impl, MethodInstance):
                inner = self._method(st, impl, wanted)
                order_in = self.conv.method_order[impl.method.name]
                _same_ids(impl.decomposition, order_in, f"method {impl.method.name}")
                work.append((iter(order_in), impl.decomposition, inner))
            else:
                self._action(st, impl, wanted)

    def _method(self, st, impl, wanted: tuple) -> dict:
        method = impl.method
        task = method.achieved_task
        if method.name not in self.conv.methods or task.task.name != st.task.name:
            raise Invalid(
                f"subtask {st.identifier} ({st.task.name}) is decomposed by "
                f"{method.name}, which is not a method of {st.task.name}"
            )
        if len(impl.parameters) != len(method.parameters):
            raise Invalid(
                f"method {method.name} takes {len(method.parameters)} parameters, "
                f"given {len(impl.parameters)}"
            )
        values = [_name(v) for v in impl.parameters]
        env = {p.name: v for p, v in zip(method.parameters, values)}
        if tuple(env[p.name] for p in task.parameters) != wanted:
            raise Invalid(
                f"method {method.name} decomposes {task.task.name}"
                f"{tuple(env[p.name] for p in task.parameters)}, not subtask "
                f"{st.identifier} {st.task.name}{wanted}"
            )
        if not self._holds(self.conv.methods[method.name], values):
            raise Invalid(
                f"the precondition of method {method.name}"
                f"({', '.join(values)}) does not hold before action "
                f"{self.next + 1} (subtask {st.identifier})"
            )
        return env

    def _action(self, st, impl, wanted: tuple) -> None:
        if impl.action.name != st.task.name or self._arguments(impl) != wanted:
            raise Invalid(
                f"subtask {st.identifier} {st.task.name}{wanted} is achieved by "
                f"{impl}, another action"
            )
        k = self.next
        if k >= len(self.actions) or not self.actions[k].is_semantically_equivalent(impl):
            what = (
                f"action {k + 1} is {self.actions[k]}"
                if k < len(self.actions)
                else "the plan has no more actions"
            )
            raise Invalid(f"subtask {st.identifier} is achieved by {impl}, but {what}")
        if not self.replay.apply_step("!" + impl.action.name, wanted):
            raise Invalid(f"action {k + 1} ({impl}) cannot be applied")  # pragma: no cover
        self.next += 1

    # ------------------------------------------------------------ helpers
    def _arguments(self, impl) -> tuple:
        from unified_planning.plans.hierarchical_plan import MethodInstance

        if isinstance(impl, MethodInstance):
            env = {p.name: _name(v) for p, v in zip(impl.method.parameters, impl.parameters)}
            return tuple(env.get(p.name) for p in impl.method.achieved_task.parameters)
        return tuple(_name(x) for x in impl.actual_parameters)

    def _holds(self, m, values: list) -> bool:
        """Whether method ``m``'s precondition holds now with its parameters
        (its first variable slots) bound to ``values``."""
        key = id(m)
        if key not in self.compiled:
            head = tuple(Var(f"p{i}", i) for i in range(len(values)))
            self.compiled[key] = self.replay.logic.precondition(m.branches[0].pre, head)
        env = [None] * m.nvars
        env[: len(values)] = values
        return next(iter(self.compiled[key](env)), None) is not None


def _same_ids(decomposition, order, owner: str) -> None:
    have = set(decomposition.subtasks)
    want = {st.identifier for st in order}
    if have != want:
        missing, extra = sorted(want - have), sorted(have - want)
        raise Invalid(
            f"the decomposition of {owner} "
            + (f"lacks subtask(s) {', '.join(missing)}" if missing else "")
            + ("; " if missing and extra else "")
            + (f"has unknown subtask(s) {', '.join(extra)}" if extra else "")
        )
