"""Why no plan: the dead ends of a search, and the deepest one in detail.

A *dead end* is a task that the search reached but could not reduce: no
operator or method of its name applied in the state of the time. For each
one that was tried the explanation says why, pointing at the source:

* its head does not match the task (a different number of arguments, or a
  constant that differs);
* its precondition has no satisfier: the first literal, in evaluation order,
  that has none under the bindings found for the literals before it;
* the operator would delete a protected atom (manual 3.9);
* (HDDL) the method instance is already being decomposed in this state
  (:mod:`htn.jshop.search.loops`), or the action breaks a goal atom that no task
  left can mend (:mod:`htn.jshop.search.goals`).

The search records a dead end only when asked (``Planner(explain=...)``), so
planning without ``--explain`` pays nothing. Where the search "got deepest"
is the dead end reached with the longest plan prefix (the first such one);
a goal that does not hold at the end of a complete decomposition is a dead
end too. ``--explain-all`` keeps every dead end, in the order met.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from htn.jshop.language import syntax as S
from htn.jshop.language.terms import atom_str, source_atom

from .unsatisfied import failing_literal
from .unsatisfied import show as _show


@dataclass
class Attempt:
    """One operator or method branch tried on a dead-end task."""

    what: str  # "operator (!pick ?x)" / "method deliver, branch m1"
    where: S.Pos | None
    reason: str
    literal_at: S.Pos | None = None

    def to_dict(self) -> dict:
        return {
            "what": self.what,
            "at": str(self.where) if self.where else None,
            "reason": self.reason,
            "literal_at": str(self.literal_at) if self.literal_at else None,
        }


@dataclass
class DeadEnd:
    task: str
    where: S.Pos | None  # where the task is written (method body or problem)
    steps: int  # plan steps before it
    attempts: list = field(default_factory=list)

    def to_dict(self) -> dict:
        return {
            "task": self.task,
            "at": str(self.where) if self.where else None,
            "after_steps": self.steps,
            "attempts": [a.to_dict() for a in self.attempts],
        }

    def lines(self, limit: int | None = None) -> list:
        at = f" ({self.where})" if self.where else ""
        out = [f"task {self.task}{at}, after {self.steps} step(s):"]
        shown = self.attempts if limit is None else self.attempts[:limit]
        for a in shown:
            where = f" ({a.where})" if a.where else ""
            lit = f" [{a.literal_at}]" if a.literal_at else ""
            out.append(f"  {a.what}{where}: {a.reason}{lit}")
        if not self.attempts:
            out.append("  no operator or method has its name")
        if limit is not None and len(self.attempts) > limit:
            out.append(f"  ... and {len(self.attempts) - limit} more")
        return out


class Explainer:
    """Collects the dead ends of one search (see the module docstring)."""

    def __init__(self, keep_all: bool = False):
        self.keep_all = keep_all
        self.cut_short = False  # the search ended at its time limit
        self.after: float | None = None  # or, replayed after the answer, at this bound (s)
        self.deepest: DeadEnd | None = None
        self.all: list = []
        self.count = 0
        self._prefixes: dict = {}

    # ------------------------------------------------------------ recording
    def dead_end(self, planner, node) -> None:
        """The task of ``node`` could not be reduced (called by the planner
        with the state as it was when the task was tried)."""
        self.count += 1
        steps = len(planner._steps)
        if not self.keep_all and self.deepest is not None and steps <= self.deepest.steps:
            return
        task = node.task
        d = DeadEnd(str(task), getattr(task.src, "pos", None), steps)
        if task.primitive:
            node.subtasks = []  # as while the search applied it
            d.attempts = self._operators(planner, task)
            node.subtasks = None
        else:
            d.attempts = self._methods(planner, task)
        self._keep(d)

    def goal_failed(self, planner) -> None:
        """A complete decomposition whose final state misses the goal."""
        self.count += 1
        inst = planner.instance
        expr = inst.goal.expr
        env = [None] * inst.goal_nvars
        item, bound = failing_literal(planner.logic, expr, env, self._prefixes)
        d = DeadEnd("the goal", inst.goal.pos, len(planner._steps))
        d.attempts = [
            Attempt(
                "goal",
                inst.goal.pos,
                f"{_show(item, bound)} does not hold in the final state",
                getattr(item, "pos", None),
            )
        ]
        self._keep(d)

    def _keep(self, d: DeadEnd) -> None:
        if self.deepest is None or d.steps > self.deepest.steps:
            self.deepest = d
        if self.keep_all:
            self.all.append(d)

    # ------------------------------------------------------------ reasons
    def _operators(self, planner, task) -> list:
        out = []
        for op, unify_head, pre, _bind, _cost in planner._ops.get(task.name, ()):
            what = f"operator {source_atom(op.head.name, op.head.args)}"
            env = [None] * op.nvars
            if not unify_head(task.args, env):
                out.append(Attempt(what, op.pos, _mismatch(op.head, task)))
                continue
            satisfiers = list(_first(pre(env), 50))
            if not satisfiers:
                item, bound = failing_literal(planner.logic, op.pre.expr, env, self._prefixes)
                out.append(
                    Attempt(
                        what,
                        op.pos,
                        f"precondition {_show(item, bound)} has no satisfier",
                        getattr(item, "pos", None),
                    )
                )
                continue
            out.append(Attempt(what, op.pos, self._why_not_applied(planner, op, satisfiers)))
        return out

    def _why_not_applied(self, planner, op, satisfiers) -> str:
        state = planner.state
        for nb in satisfiers:
            dels, _adds = planner.effects(op, nb)
            change, ok = planner._apply(op, nb)
            broken = (
                ok
                and planner.guard is not None
                and planner.guard.broken(change, state, planner.root)
            )
            change.undo(state)
            if not ok:
                protected = [atom_str(*a) for a in dels if state.is_protected(*a)]
                atom = f" {protected[0]}" if protected else ""
                return f"it would delete the protected atom{atom} (manual 3.9)"
            if broken:
                return "it breaks a goal atom that no task left can make true again"
        return "it applies, but no plan continues from it"  # pragma: no cover

    def _methods(self, planner, task) -> list:
        out = []
        methods = planner._methods.get(task.name, ())
        for m, unify_head, branches, _index in methods:
            env = [None] * m.nvars
            if not unify_head(task.args, env):
                out.append(
                    Attempt(
                        f"method {source_atom(m.head.name, m.head.args)}",
                        m.pos,
                        _mismatch(m.head, task),
                    )
                )
                continue
            for k, (sat, _reduce, _ordered) in enumerate(branches):
                branch = m.branches[k]
                what = f"method {source_atom(m.head.name, m.head.args)}, branch {branch.label}"
                satisfiers = list(_first(sat(env), 1))
                if satisfiers:
                    out.append(
                        Attempt(
                            what,
                            branch.pos or m.pos,
                            "every binding of its "
                            "precondition is already being decomposed in this "
                            "state (a loop)",
                        )
                    )
                    break  # JSHOP2: later branches are not considered
                item, bound = failing_literal(planner.logic, branch.pre.expr, env, self._prefixes)
                out.append(
                    Attempt(
                        what,
                        branch.pos or m.pos,
                        f"precondition {_show(item, bound)} has no satisfier",
                        getattr(item, "pos", None),
                    )
                )
        return out

    # ------------------------------------------------------------ output
    def lines(self, full: bool = False) -> list:
        short = ["explain: the time limit ended the search, these are the dead ends met by then"]
        if self.after is not None:
            short = [
                f"explain: depth-first search, replayed to explain the answer, was stopped "
                f"after {self.after:.1f} s (the time the search took, at least 1 s); the dead "
                "ends met by then"
            ]
        return (short if self.cut_short else []) + self._lines(full)

    def _lines(self, full: bool) -> list:
        if self.deepest is None:
            return ["explain: the search met no dead end"]
        if full:
            out = [f"explain: {self.count} dead end(s), in the order met:"]
            for d in self.all:
                out += ["  " + line for line in d.lines()]
            return out
        return [
            f"explain: the search got deepest at this dead end ({self.count} in all; "
            "--explain-all lists every one):"
        ] + ["  " + line for line in self.deepest.lines(limit=12)]

    def to_dict(self, full: bool = False) -> dict:
        d: dict = {
            "dead_ends": self.count,
            "deepest": self.deepest.to_dict() if self.deepest else None,
            "cut_short": self.cut_short,
        }
        if full:
            d["all"] = [x.to_dict() for x in self.all]
        return d


def explain_search(
    domain,
    instance,
    functions=None,
    keep_all: bool = False,
    timeout: float | None = None,
    **options,
) -> Explainer:
    """Run a whole search of ``instance`` recording its dead ends, for at
    most ``timeout`` seconds (then ``cut_short`` is set: the dead ends are
    those met so far)."""
    from htn.jshop.search.planner import Planner

    explainer = Explainer(keep_all=keep_all)
    planner = Planner(domain, instance, functions, explain=explainer, **options)
    for _ in planner.plans(timeout):
        pass
    explainer.cut_short = planner.stats.timed_out
    return explainer


def _first(it, n: int):
    for i, x in enumerate(it):
        if i >= n:
            return
        yield x


def _mismatch(head: S.TaskAtom, task) -> str:
    if len(head.args) != len(task.args):
        return f"its head takes {len(head.args)} argument(s), the task has {len(task.args)}"
    return "its head does not match the task's arguments"
