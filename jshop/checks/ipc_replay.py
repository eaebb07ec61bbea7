"""The execution check of an IPC plan (:mod:`htn.jshop.checks.ipc_verify`,
step 5): the actions in the order written, from the initial state, with each
applied method's precondition tested where the method may be applied.

The plan is a graph (the IPC 2020 verifier's): a vertex per action, and a
start and an end per decomposed task; a task's start comes before its
subtasks' and their ends before its end, an ordering constraint ``a < b``
of its method puts ``a``'s end before ``b``'s start, and each action comes
after the one written before it. Starts and ends are taken as early as this
order allows, a start only in a state where its method's precondition holds
(re-tested after each action while it waits); an action whose turn comes
before a start it depends on was taken means that start's precondition held
in no state where it could be (between the last action ordered before the
task and the first action below it). No branching: HDDL methods have no
effects, so taking a start as early as possible never loses a plan.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

from htn.jshop.plans.plan import Step

from .unsatisfied import failing_literal, show
from .validate import why_goal, why_step


@dataclass
class Finding:
    """A reason why a plan is invalid, at its line and column."""

    line: int
    col: int
    message: str


class Replay:
    """The actions in order, each method's start and end placed as early as
    the ordering and its precondition allow (a start waits, re-tested after
    each action, while its precondition is false)."""

    def __init__(self, check, chosen: dict):
        self.c, self.chosen = check, chosen
        self.succ: dict = {}
        self.indeg: dict = {}
        self.preds: dict = {}
        self.compiled: dict = {}
        actions = check.plan.actions
        for ident, match in chosen.items():
            d, sh = check._decomposition(ident), check.shape_of[ident]
            self.edge(("s", ident), ("e", ident))
            for c in d.children:
                self.edge(("s", ident), self.first(c))
                self.edge(self.last(c), ("e", ident))
            child = {i: d.children[k] for k, i in enumerate(match.order)}
            for i, j in sh.pairs:
                self.edge(self.last(child[i]), self.first(child[j]))
        for a, b in zip(actions, actions[1:]):
            self.edge(("a", a.id), ("a", b.id))
        for a in actions:
            self.indeg.setdefault(("a", a.id), 0)

    def first(self, ident: int) -> tuple:
        return ("s", ident) if ident in self.chosen else ("a", ident)

    def last(self, ident: int) -> tuple:
        return ("e", ident) if ident in self.chosen else ("a", ident)

    def edge(self, v: tuple, w: tuple) -> None:
        self.succ.setdefault(v, []).append(w)
        self.preds.setdefault(w, []).append(v)
        self.indeg[w] = self.indeg.get(w, 0) + 1
        self.indeg.setdefault(v, 0)

    def holds(self, ident: int) -> bool:
        sh = self.c.shape_of[ident]
        sat = self.compiled.get(id(sh))
        if sat is None:
            sat = self.compiled[id(sh)] = self.c.planner.logic.precondition(sh.pre, sh.bound)
        return next(iter(sat(list(self.chosen[ident].env))), None) is not None

    def run(self) -> list:
        c, planner = self.c, self.c.planner
        work = deque(v for v, n in self.indeg.items() if n == 0 and v[0] != "a")
        ready: set = {v[1] for v, n in self.indeg.items() if n == 0 and v[0] == "a"}
        blocked: list = []
        self.done: set = set()

        def take(v: tuple) -> None:
            self.done.add(v)
            for w in self.succ.get(v, ()):
                self.indeg[w] -= 1
                if self.indeg[w] == 0:
                    if w[0] == "a":
                        ready.add(w[1])
                    else:
                        work.append(w)

        for a in [*c.plan.actions, None]:
            while work:
                v = work.popleft()
                if v[0] == "s" and not self.holds(v[1]):
                    blocked.append(v[1])
                else:
                    take(v)
            if a is None:
                break
            if a.id not in ready:
                return [self.blame(a)]
            step = Step("!" + a.name, a.args, line=a.line)
            option = next(iter(planner.step_options(step.name, step.args)), None)
            if option is None or planner.apply(*option) is None:
                return [Finding(a.line, a.cols[0], f"action id {a.id}: {why_step(planner, step)}")]
            take(("a", a.id))
            work.extend(("s", x) for x in blocked)
            blocked = []
        if blocked:
            return [self.precondition_fails(blocked[0], "after the last action")]
        goal = c.instance.goal
        if goal is not None and not planner.goal_holds():
            return [Finding(c.plan.end_line, 1, why_goal(planner, c.instance))]
        return []

    def blame(self, a) -> Finding:
        """Why action ``a`` cannot come next: the method start it waits for."""
        stack, seen = [("a", a.id)], set()
        while stack:
            v = stack.pop()
            for p in self.preds.get(v, ()):
                if p in self.done or p in seen:
                    continue
                seen.add(p)
                if p[0] == "s" and all(q in self.done for q in self.preds.get(p, ())):
                    return self.precondition_fails(p[1], f"before action id {a.id} (line {a.line})")
                stack.append(p)
        return Finding(
            a.line,
            a.col,
            f"action id {a.id} comes before an action the decomposition orders before it",
        )

    def precondition_fails(self, ident: int, where: str) -> Finding:
        c = self.c
        d, sh = c._decomposition(ident), c.shape_of[ident]
        item, bound = failing_literal(c.planner.logic, sh.pre.expr, list(self.chosen[ident].env))
        why = f": {show(item, bound)} has no satisfier" if item is not None else ""
        what = (
            "the problem's initial task network"
            if ident < 0
            else f"id {ident} ({d.text}) -> {sh.name}"
        )
        return Finding(
            d.line,
            d.method_col,
            f"{what}: the method's precondition does not hold "
            f"{where}, nor earlier where it may be applied{why}",
        )
