"""The symbolic robot: runs any JSHOP2 plan against the domain's own operators.

Its world is the problem's initial state. Executing a step applies the
operator's effects exactly as the planner does (manual 5.2.1: the operator
whose head unifies with the step, under the first satisfier of its
precondition in the current world); the monitor then checks the operator's
add and delete lists against the world: every added atom holds, every deleted
one (that the operator does not add back) is gone. A step whose precondition
does not hold in the world fails.

The injected faults, so that monitors, retries, repair and the log can be
exercised with any domain: ``effect=P``, with probability P an execution's
effects do not happen at all (an actuator that reports success but did
nothing: the monitor catches it, the action is ``aborted``); ``fail=P``, an
execution reports an internal failure and does nothing (a driver error: the
action is ``failed``, which only repair may try again).
Each action takes one second of simulated time.
"""

from __future__ import annotations

import random

from htn.jshop.language import syntax as S
from htn.jshop.language.terms import atom_str

from .interface import Check, Robot, SkillResult, check, skill

ACTION_TIME = 1.0


class SymbolicRobot(Robot):
    """Executes operators on a symbolic world: the domain's operator model."""

    FAULTS = ("effect", "fail")
    executes_operator_model = True
    instantaneous = True

    def __init__(
        self,
        domain: S.Domain,
        instance: S.ProblemInstance,
        functions=None,
        faults: dict | None = None,
        seed: int = 0,
    ):
        from htn.jshop.search.planner import Planner

        self.model = Planner.for_state(domain, instance.state, functions)
        self.world = self.model.state
        self.dynamic = domain.dynamic_predicates()
        self.effect_fault = (faults or {}).get("effect", 0.0)
        self.fail_fault = (faults or {}).get("fail", 0.0)
        self.rng = random.Random(seed)
        self.sim_time = 0.0
        self.injected: list[dict] = []
        self._expected: dict = {}  # (name, args) -> (deleted, added) of its last execution

    @skill("operator")
    def apply_operator(self, name: str, args: tuple) -> SkillResult:
        args = tuple(args)
        self.sim_time += ACTION_TIME
        step = atom_str(name, args)
        if self.fail_fault and self.rng.random() < self.fail_fault:
            self.inject("fail", f"{step} reports an internal failure")
            return SkillResult(
                False,
                f"internal failure: the skill for {step} stopped with an error and did nothing",
            )
        for op, env in self.model.step_options(name, args):
            deleted, added = self.model.effects(op, env)
            change = self.model.apply(op, env)
            if change is None:
                continue  # it would delete a protected atom: try the next option
            # what the operator model did, as JSHOP2 applies it (a forall
            # effect deleting while it enumerates may leave atoms in place)
            state = self.world
            self._expected[(name, args)] = (
                [a for a in deleted if not state.has(*a)],
                [a for a in added if state.has(*a)],
            )
            if self.effect_fault and self.rng.random() < self.effect_fault:
                change.undo(state)
                self.inject("effect", f"the effects of {step} do not happen")
            return SkillResult(True, f"executed {step}")
        return SkillResult(False, f"the precondition of {step} does not hold in the world")

    @check("operator_effects")
    def check_operator_effects(self, name: str, args: tuple) -> Check:
        expected = self._expected.get((name, tuple(args)))
        if expected is None:
            return Check(False, f"{atom_str(name, args)} was not executed")
        deleted, added = expected
        state = self.world
        missing = [a for a in added if not state.has(*a)]
        kept = [a for a in deleted if state.has(*a)]
        if not missing and not kept:
            return Check(True, f"{len(added)} added, {len(deleted)} deleted atom(s) observed")
        wrong = [f"{atom_str(*a)} missing" for a in missing] + [
            f"{atom_str(*a)} still holds" for a in kept
        ]
        more = f" (+{len(wrong) - 3} more)" if len(wrong) > 3 else ""
        return Check(False, "; ".join(wrong[:3]) + more)

    def apply_internal(self, name: str, args: tuple) -> None:
        self.model.apply_step(name, tuple(args))

    def observe(self) -> list[tuple[str, tuple]]:
        return [(p, a) for p, a in self.world.facts() if p in self.dynamic]
