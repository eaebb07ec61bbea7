"""Verify a plan in the IPC 2020 HTN format: its decomposition and its actions.

An IPC plan (:mod:`htn.jshop.plans.ipc`) is valid for an HDDL problem when
(Höller et al., AAAI 2020; the checks of the IPC 2020 verifier,
pandaPIparser's ``--verify``), in this order:

1. **ids**: every id is defined once, by an action line or a decomposition
   line; every id a line lists exists and is not the line's own; every id is
   reached from the ``root`` line exactly once (no id has two parents, none
   is left out);
2. **names**: an action line names an action of the domain, a decomposition
   line a compound task (or the artificial ``__top``), each with its arity
   and with arguments that are objects of the parameters' types;
3. **methods**: each decomposition line names a method of its task that it
   instantiates (:mod:`htn.jshop.checks.ipc_match`: the task's arguments, the
   listed subtasks in an order the method allows, the parameters' types);
   the root ids instantiate the problem's initial task network the same way;
4. **order**: for each ordering constraint ``a < b`` of an applied method,
   every action below ``a`` comes before every action below ``b``;
5. **execution**: the actions, in the order written, are applicable from the
   initial state, and each method's precondition holds in a state where it
   is applied: between the last action ordered before the method's task and
   the first action below it (the verifier's greedy topological execution:
   the precondition is tested from the earliest such state on); the goal
   holds in the final state.

A plan that fails a step is invalid; the findings of the first failing step
are its reasons, each at ``line:col`` of the plan file. Names compare
case-insensitively (HDDL's names are), where the verifier compares them as
the files write them; lines that list each other in a cycle apart from the
root are not reached from it, where the verifier only asks that every id be
listed by some line.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError
from htn.jshop.plans.ipc import IpcLine, IpcPlan

from .ipc_match import TOP, TOP_METHOD, Shapes, matchings, top_shape
from .ipc_replay import Finding, Replay

MAX_COMBINATIONS = 256  # ambiguous matchings tried together in the execution check


@dataclass
class IpcVerdict:
    valid: bool
    actions: int
    decompositions: int
    findings: list = field(default_factory=list)


def verify_ipc_plan(
    domain: S.Domain, problem: S.Problem, plan: IpcPlan, functions=None
) -> IpcVerdict:
    """Check ``plan`` against an HDDL domain and problem (module docstring)."""
    if domain.hddl is None or problem.hddl is None:
        raise HtnError.at(
            domain.pos if domain.hddl is None else problem.pos,
            "an IPC plan is checked against an HDDL domain and problem",
        )
    return _Check(domain, problem, plan, functions).run()


class _Check:
    def __init__(self, domain: S.Domain, problem: S.Problem, plan: IpcPlan, functions):
        self.domain, self.plan, self.functions = domain, plan, functions
        self.h = domain.hddl
        self.instance = problem.instances[0]
        self.shapes = Shapes(self.h)
        self.top_shape = top_shape(problem.hddl, self.h.predicates)
        self.findings: list = []
        self.lines: dict = {}
        self.top: IpcLine | None = None  # the decomposition line of the root (maybe made up)
        self.planner = self._planner()
        self.shape_of: dict = {}  # id -> Shape
        self.choices: dict = {}  # id -> [Match]

    def _planner(self):
        from htn.jshop.search.planner import Planner

        inst = self.instance
        return Planner.for_state(
            self.domain, inst.state, self.functions, goal=inst.goal, goal_nvars=inst.goal_nvars
        )

    def add(self, line: int, col: int, message: str) -> None:
        self.findings.append(Finding(line, col, message))

    def run(self) -> IpcVerdict:
        for step in (self.ids, self.names, self.methods, self.order, self.execution):
            step()
            if self.findings:
                break
        plan = self.plan
        return IpcVerdict(
            not self.findings, len(plan.actions), len(plan.decompositions), self.findings
        )

    # ------------------------------------------------------------ 1. ids
    def ids(self) -> None:
        plan = self.plan
        for e in (*plan.actions, *plan.decompositions):
            if e.id in self.lines:
                self.add(
                    e.line,
                    e.col,
                    f"id {e.id} is used twice (first on line {self.lines[e.id].line})",
                )
            else:
                self.lines[e.id] = e
        if not plan.root_line:
            self.add(plan.end_line, 1, "the plan has no 'root' line")
            return
        first = self.lines.get(plan.root[0]) if len(plan.root) == 1 else None
        if first is not None and first.method is not None and first.name == TOP:
            self.top = first
        else:
            self.top = IpcLine(
                -1, TOP, (), plan.root_line, 1, (1,), TOP_METHOD, 1, plan.root, plan.root_cols
            )
        parent: dict = {}
        self._refer("the root", None, plan.root, plan.root_cols, plan.root_line, parent)
        for d in plan.decompositions:
            self._refer(
                f"id {d.id} (line {d.line})", d.id, d.children, d.child_cols, d.line, parent
            )
        reached, stack = set(), [i for i in plan.root if i in self.lines]
        while stack:  # from the root: a cycle of lines that list each other is not
            i = stack.pop()
            if i not in reached:
                reached.add(i)
                stack.extend(c for c in self.lines[i].children if c in self.lines)
        for e in (*plan.actions, *plan.decompositions):
            if e.id not in reached and self.lines.get(e.id) is e:
                why = (
                    "no line lists it as a subtask"
                    if e.id not in parent
                    else f"it is a subtask of {parent[e.id]}, which is not reached either"
                )
                self.add(
                    e.line, e.col, f"id {e.id} ({e.text}) is not reached from the root: " + why
                )

    def _refer(self, owner: str, own, ids, cols, line: int, parent: dict) -> None:
        for i, col in zip(ids, cols):
            if i == own:
                self.add(line, col, f"id {i} lists itself as a subtask")
            elif i not in self.lines:
                self.add(
                    line,
                    col,
                    f"subtask id {i} is not defined: no action or decomposition line has it",
                )
            elif i in parent:
                self.add(line, col, f"id {i} is already a subtask of {parent[i]}")
            else:
                parent[i] = owner

    # ------------------------------------------------------------ 2. names
    def of_type(self, obj: str, types) -> bool:
        has = self.planner.state.has
        return any(has("type:" + t, (obj,)) for t in types)

    def names(self) -> None:
        h = self.h
        for e in self.plan.actions:
            a = h.actions.get(e.name)
            if a is None:
                self.add(
                    e.line,
                    e.cols[0],
                    f"{e.name} is a compound task, not an action: it "
                    "needs a decomposition line after 'root'"
                    if e.name in h.tasks
                    else f"the domain has no action {e.name}",
                )
            else:
                self._arguments(e, a.params, "action")
        for d in self.plan.decompositions:
            if d.name == TOP:
                if d is not self.top:
                    self.add(d.line, d.cols[0], f"{TOP} can only be the one root task")
                continue
            t = h.tasks.get(d.name)
            if t is None:
                self.add(
                    d.line,
                    d.cols[0],
                    f"{d.name} is an action, not a compound task: it cannot be decomposed"
                    if d.name in h.actions
                    else f"the domain has no task {d.name}",
                )
            else:
                self._arguments(d, t.params, "task")

    def _arguments(self, e: IpcLine, params: list, kind: str) -> None:
        if len(params) != len(e.args):
            self.add(
                e.line,
                e.cols[0],
                f"{kind} {e.name} takes {len(params)} argument(s), given {len(e.args)}",
            )
            return
        for k, (value, p) in enumerate(zip(e.args, params)):
            if not self.of_type(value, p.types):
                self.add(
                    e.line,
                    e.cols[k + 1],
                    f"argument {k + 1} of {e.name}, {value}, is not "
                    f"an object of type {' or '.join(p.types)}",
                )

    # ------------------------------------------------------------ 3. methods
    def methods(self) -> None:
        top = self.top
        assert top is not None  # set by ids()
        for d in (*self.plan.decompositions, *([top] if top.id < 0 else [])):
            if d.name == TOP:
                sh, why = (
                    self.top_shape,
                    (
                        ""
                        if d.method == TOP_METHOD
                        else f"the root task {TOP} is decomposed by {TOP_METHOD}"
                    ),
                )
            else:
                assert d.method is not None  # a decomposition line names its method
                sh, why = self.shapes.get(d.name, d.method)
            if why:
                self.add(d.line, d.method_col, why)
                continue
            children = [(self.lines[c].name, self.lines[c].args) for c in d.children]
            found, mismatch = matchings(sh, d.args, children, self.of_type)
            if not found:
                col = d.child_cols[mismatch.at] if mismatch.at is not None else d.method_col
                what = (
                    "the root tasks are not the problem's initial task network"
                    if d.id < 0
                    else f"id {d.id} ({d.text}) -> {d.method}"
                )
                self.add(d.line, col, f"{what}: {mismatch.message}")
                continue
            self.shape_of[d.id] = sh
            self.choices[d.id] = found

    def _decomposition(self, ident: int) -> IpcLine:
        assert self.top is not None  # set by ids()
        return self.top if ident == self.top.id else self.lines[ident]

    # ------------------------------------------------------------ 4. order
    def order(self) -> None:
        span = self._spans()
        for ident, found in self.choices.items():
            d, sh = self._decomposition(ident), self.shape_of[ident]
            kept: list = []
            first_bad: tuple | None = None
            for match in found:
                child = {i: d.children[k] for k, i in enumerate(match.order)}
                bad = next(
                    ((i, j) for i, j in sh.pairs if _after(span[child[i]], span[child[j]])), None
                )
                if bad is None:
                    kept.append(match)
                elif first_bad is None:
                    first_bad = (bad, child)
            if kept:
                self.choices[ident] = kept
                continue
            assert first_bad is not None  # found is not empty: every match kept or bad
            (i, j), child = first_bad
            a = self.plan.actions[span[child[i]][1]]
            b = self.plan.actions[span[child[j]][0]]
            self.add(
                d.line,
                d.child_cols[d.children.index(child[j])],
                f"method {sh.name} orders {_label(sh, i)} (id {child[i]}) before "
                f"{_label(sh, j)} "
                f"(id {child[j]}), but action id {a.id} (line {a.line}) comes after action "
                f"id {b.id} (line {b.line})",
            )

    def _spans(self) -> dict:
        """id -> (first, last) position of the actions below it, () if none;
        bottom-up over the tree (steps 1-3 made it one), without recursion."""
        assert self.top is not None  # set by ids()
        span: dict[int, tuple[int, ...]]  # (first, last) or ()
        span = {a.id: (k, k) for k, a in enumerate(self.plan.actions)}
        stack = [(self.top.id, False)]
        while stack:
            ident, expanded = stack.pop()
            if ident in span:
                continue
            children = self._decomposition(ident).children
            if not expanded:
                stack.append((ident, True))
                stack.extend((c, False) for c in children)
                continue
            below = [span[c] for c in children if span[c]]
            span[ident] = (min(b[0] for b in below), max(b[1] for b in below)) if below else ()
        return span

    # ------------------------------------------------------------ 5. execution
    def execution(self) -> None:
        ambiguous = [i for i, ms in self.choices.items() if len(ms) > 1]
        fixed = {i: ms[0] for i, ms in self.choices.items()}
        first: list | None = None
        options = [self.choices[i] for i in ambiguous]
        for combo in itertools.islice(itertools.product(*options), MAX_COMBINATIONS):
            chosen = {**fixed, **dict(zip(ambiguous, combo))}
            if combo or first is not None:
                self.planner = self._planner()
            findings = Replay(self, chosen).run()
            if not findings:
                return
            first = first or findings
        assert first is not None  # product() gives at least one combination
        self.findings += first


def _label(sh, k: int) -> str:
    return sh.subtasks[k][2] or f"subtask {k + 1}"


def _after(before: tuple, after: tuple) -> bool:
    """Whether some action of ``before`` (first, last positions) comes after
    some action of ``after``."""
    return bool(before) and bool(after) and before[1] > after[0]


def verify_ipc_text(
    domain: S.Domain, problem: S.Problem, text: str, file: str, plan_index=None, functions=None
) -> list:
    """``[(IpcPlan, IpcVerdict)]`` for the IPC plans of a file's ``text`` (the
    ``plan_index``-th only, 1-based, if given); :class:`HtnError` for a file
    that cannot be read as IPC plans."""
    from htn.jshop.plans.ipc import read_ipc_plans

    plans = read_ipc_plans(text, file)
    if plan_index is not None:
        if plan_index > len(plans):
            raise HtnError(f"--plan-index {plan_index}: the file holds {len(plans)} plan(s)", file)
        plans = [plans[plan_index - 1]]
    return [(p, verify_ipc_plan(domain, problem, p, functions)) for p in plans]
