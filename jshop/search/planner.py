"""The JSHOP2 search (manual sections 4 and 5.2.3; JSHOP2's ``findPlanHelper``).

The task network is a tree of :class:`Node` s that is rewritten in place and
restored on backtracking, as in JSHOP2:

* the tasks that may be done next are the first tasks of the network
  (:func:`first_tasks`); an ``:immediate`` one among them is the only option;
* a primitive task is tried with every operator of its name, in definition
  order, and every satisfier of the operator's precondition; the operator is
  applied unless it would delete a protected atom, and the search goes on with
  the whole network;
* a compound task is tried with every method of its name, in definition order;
  within a method the branches are if-then-else (a branch is considered only if
  no earlier branch had a satisfier), and every satisfier of the chosen branch
  is an alternative. The search then continues *inside* the reduced task until
  it reaches an operator, as JSHOP2 does.

Plans come out as a lazy stream in JSHOP2's order, so the first N plans of the
stream are what ``-rN`` prints and the whole stream is ``-ra``. The recursion of
``findPlanHelper`` is run as an explicit stack of generator frames, so plan
length is not limited by Python's recursion limit.

A method body written ``(:unordered ...)`` is unordered, as the manual says
(3.8, 5.2.2: the reduced task is replaced by the body, flag included). JSHOP2
1.0.3 differs: its ``TaskList.replace`` keeps the reduced task's "ordered"
flag, so such a body runs in order. ``jshop2_compat=True`` reproduces that
(nested ``:unordered`` lists keep their meaning in both modes).

The reduction depth (nested reductions since the last operator applied on
the current path) is bounded by ``max_depth``, and the search's memory by a
:class:`htn.jshop.search.limits.MemoryGuard` (see :mod:`htn.jshop.search.limits`): a method
that decomposes into itself without end would otherwise grow the stack until
memory runs out (JSHOP2 ends such a search with a ``StackOverflowError``).
Reaching a bound ends the search like a timeout; ``stats.bound`` then
says which bound, and names the task that was being reduced deepest.
"""

from __future__ import annotations

import gc
import time
from collections.abc import Generator

from htn.jshop.language import syntax as S
from htn.jshop.language.errors import PlanningError
from htn.jshop.language.terms import shown_term, subst, variables
from htn.jshop.logic.engine import Logic
from htn.jshop.logic.operators import Operators
from htn.jshop.logic.state import Change, HashedState, State
from htn.jshop.plans.plan import Plan, Step
from htn.jshop.plans.tree import snapshot

from .ancestry import loop_check_for
from .goals import GoalGuard
from .limits import DEFAULT_MAX_DEPTH, DepthLimit, MemoryGuard, MemoryLimit
from .needs import NeedGuard
from .network import Node, bind_tasks, deepest_task, first_in_order, first_tasks, undo_marks
from .prune import dead_methods
from .stats import Stats
from .steps import method_entry, operator_entry
from .threats import ThreatOrder

_PLAN = object()


def _indexed(entry: list, index: int) -> list:
    """A method's entry with its place among its task's methods (the entry
    itself: warming replaces its head unifier in place)."""
    entry.append(index)
    return entry


class Planner:
    """Finds plans for one problem instance of a domain."""

    def __init__(
        self,
        domain: S.Domain,
        instance: S.ProblemInstance,
        functions=None,
        record_trees: bool = False,
        jshop2_compat: bool = False,
        max_depth: int = DEFAULT_MAX_DEPTH,
        loop_check: bool | None = None,
        explain=None,
        max_memory: int | None = None,
        tree_paths: bool = True,
        prune: bool = True,
        guards: bool = True,
    ):
        self.domain = domain
        self.explain = explain  # an explain.Explainer collecting dead ends, or None
        self.instance = instance
        self.record_trees = record_trees
        self.tree_paths = tree_paths  # node paths in recorded trees (see tree.snapshot)
        self.max_depth = max_depth
        self.max_memory = max_memory  # bytes, or None for the default budget
        if loop_check is None:  # on for HDDL, off for JSHOP2 (its own semantics)
            loop_check = domain.language == "hddl"
        self.state = HashedState() if loop_check else State()
        self.loops = loop_check_for(domain, instance, self.state) if loop_check else None
        implied = domain.implied
        for atom in (*domain.facts, *instance.state):
            self.state.add(atom.pred, atom.args)
            for pred in implied.get(atom.pred, ()):  # HDDL supertypes
                self.state.add(pred, atom.args)
        self.logic = Logic(domain, self.state, functions)
        self.operators = Operators(self.state, self.logic)
        self._apply = self.operators.apply
        self._goal: tuple | None = None  # (precondition, its number of variables)
        self.guard: GoalGuard | None = None
        if instance.goal is not None:
            self._goal = (self.logic.precondition(instance.goal), instance.goal_nvars)
            self.guard = GoalGuard(domain, instance.goal) or None
        # HDDL (with ``guards``): cut once a task left needs an atom no action
        # can add back (needs.py); a method's bindings that take what a later
        # action needs go last (threats.py)
        guards = guards and loop_check
        self.needs = (NeedGuard(domain) or None) if guards else None
        threats = (ThreatOrder(domain) or None) if guards else None
        self.threats = threats
        self._threatening = (
            {
                m.name
                for ms in domain.methods.values()
                for m in ms
                if any(t.name in threats.dels for b in m.branches for t in S.task_atoms(b.tasks))
            }
            if threats is not None
            else set()
        )
        # (operator, head unifier, precondition, head substituter, constant cost or None)
        self._ops = {
            name: [operator_entry(self.logic, op) for op in ops]
            for name, ops in domain.operators.items()
        }
        # (method, head unifier, [(precondition, body, body is ordered)] per branch,
        # its place among its task's methods); HDDL methods that cannot apply
        # from this initial state are left out (see prune.py), unless explained
        dead = dead_methods(domain, instance) if prune and explain is None else set()
        self.pruned = len(dead)
        self._methods = {
            name: [
                _indexed(method_entry(self.logic, m, jshop2_compat), i)
                for i, m in enumerate(ms)
                if (name, i) not in dead
            ]
            for name, ms in domain.methods.items()
        }
        self.stats = Stats()
        # the problem's own variables (if any) stay unbound, like a method's
        nvars = 1 + max(
            (v.index for t in S.task_atoms(instance.tasks) for v in variables(t.args, [])),
            default=-1,
        )
        if instance.top is not None:  # HDDL: a root task binds the network's parameters
            m = S.root_method(instance)
            self._methods[m.name] = [_indexed(method_entry(self.logic, m, False), 0)]
            self.root = bind_tasks(S.TaskList([m.head]), [])
        else:
            self.root = bind_tasks(instance.tasks, [None] * nvars)
        self._steps: list = []
        self._cost = 0.0
        self._trail: list = []  # nodes marked done, see first_tasks
        self._cursor: list = []  # where the last walk found its task, see _first
        self._cursor_ok = False
        self.slice_s: float | None = None  # CPU s between pauses: see plans()

    # ------------------------------------------------------------ driver
    def plans(self, timeout: float | None = None) -> Generator[Plan | None, None, None]:
        """Stream plans in JSHOP2's order until exhausted or ``timeout``.

        ``stats.elapsed`` counts search time only, not the time the consumer
        spends between plans; ``timeout`` is wall-clock time since the start.
        With ``slice_s`` set, None is yielded after each such slice of CPU time.
        """
        stats = self.stats
        clock = time.perf_counter
        # The search allocates many short-lived lists and generators but makes
        # no reference cycles (the network is a tree, frames sit on an explicit
        # stack), so reference counting frees everything; the cyclic collector
        # would only rescan. It is paused while searching, never while the
        # consumer runs.
        gc_was_enabled = gc.isenabled()
        gc.disable()
        t0: float | None
        t0 = stats.started = clock()
        spent = 0.0
        frame = self._frame
        root = self.root
        stack = [frame(root)]
        depths = [0]  # per frame: reductions since the last step on its path
        push, pop, nxt = stack.append, stack.pop, next
        dpush, dpop = depths.append, depths.pop
        max_depth = self.max_depth
        guard = None  # made at the first check: tiny searches never pay for it
        pause_at = None if self.slice_s is None else time.process_time() + self.slice_s
        ticks = stats.expansions
        stats.expansions += 1
        try:
            while stack:
                req = nxt(stack[-1], None)  # frames never yield None
                if req is None:
                    pop()
                    dpop()
                    continue
                if req is _PLAN:
                    stats.plans_found += 1
                    plan = Plan(
                        [Step(*s) for s in self._steps], self._cost, index=stats.plans_found - 1
                    )
                    if self.record_trees:
                        plan.tree = snapshot(self.root, plan.steps, self.tree_paths)
                    spent += clock() - t0
                    stats.elapsed = spent
                    stats.expansions = ticks + 1
                    t0 = None  # the consumer's time is not search time
                    if gc_was_enabled:
                        gc.enable()
                    yield plan
                    gc.disable()
                    t0 = clock()
                    continue
                if req is root:  # an operator was applied (or a task list ended)
                    depth = 0
                else:
                    depth = depths[-1] + 1
                    if depth >= max_depth:
                        stats.bound = DepthLimit(max_depth, deepest_task(root, req))
                        return
                push(frame(req))
                dpush(depth)
                ticks += 1
                if not ticks & 255:
                    if timeout is not None and clock() - stats.started > timeout:
                        stats.timed_out = True  # wall clock, output included
                        return
                    if pause_at is not None and time.process_time() >= pause_at:
                        spent += clock() - t0
                        stats.expansions = ticks + 1  # what the portfolio sees
                        yield None  # see slice_s: another search's turn
                        assert self.slice_s is not None  # the portfolio sets it before each turn
                        t0, pause_at = clock(), time.process_time() + self.slice_s
                    if not ticks & 4095:
                        if guard is None:
                            guard = MemoryGuard(self.max_memory)
                        if guard.exceeded():
                            stats.bound = MemoryLimit(guard.limit_bytes, deepest_task(root, req))
                            return
        except KeyboardInterrupt:
            stats.interrupted = True
            raise
        finally:
            stats.elapsed = spent + (clock() - t0 if t0 is not None else 0.0)
            stats.expansions = ticks + 1
            if self.loops is not None:
                stats.loop_cuts = self.loops.cut
            for frame in reversed(stack):
                frame.close()
            if gc_was_enabled:
                gc.enable()

    # ------------------------------------------------------------ one frame
    def _frame(self, chosen: Node):
        """One call of JSHOP2's ``findPlanHelper(chosen)``, as a generator.

        It yields a node to recurse into (the driver runs that call and then
        resumes this one) or ``_PLAN`` when the whole network is achieved.
        """
        trail = self._trail
        loops = self.loops
        mark = len(trail)
        options = self._first(chosen, trail)
        if loops is not None and len(trail) > mark:
            loops.completed(trail, mark)
        mark = len(trail)
        if not options:
            if chosen is not self.root:
                yield self.root
                self._cursor_ok = False
            elif self._goal is None or self.goal_holds():
                yield _PLAN
                self._cursor_ok = False
            elif self.explain is not None:
                self.explain.goal_failed(self)
            return
        state = self.state
        explain = self.explain
        root = self.root
        for node in options:
            task = node.task
            tried = False  # did any operator or method apply?
            if task.primitive:
                node.subtasks = []
                steps, apply, guard, needs = self._steps, self._apply, self.guard, self.needs
                for op, unify_head, pre, bind_head, cost in self._ops.get(task.name, ()):
                    env = [None] * op.nvars
                    if not unify_head(task.args, env):
                        continue
                    for nb in pre(env):
                        change, ok = apply(op, nb)
                        if (
                            ok
                            and guard is not None
                            and guard.broken(
                                change, state, root, self._cursor if self._cursor_ok else None
                            )
                        ):
                            ok = False
                        if (
                            ok
                            and needs is not None
                            and change.deleted
                            and needs.broken(
                                change, state, root, self._cursor if self._cursor_ok else None
                            )
                        ):
                            ok = False
                        if ok:
                            self.stats.operator_applications += 1
                            if cost is None:  # a cost term: evaluate it
                                cost = subst(op.cost, nb)
                                if type(cost) is not float:
                                    raise PlanningError.at(
                                        op.pos,
                                        f"cost of {op.name} is {shown_term(cost)}, not a number",
                                    )
                            node.how = len(steps)
                            steps.append((op.name, bind_head(nb), cost))
                            self._cost += cost
                            tried = True
                            yield root
                            self._cursor_ok = False
                            if len(trail) > mark:
                                undo_marks(trail, mark, loops)
                            steps.pop()
                            self._cost -= cost
                            if type(op.cost) is not float:
                                cost = None
                        change.undo(state)
                node.subtasks = None
                node.how = None
            else:
                methods = self._methods.get(task.name, ())
                needs, threats = self.needs, self.threats
                key = None
                if loops is not None:
                    key = loops.key(task)
                    if key in loops.active and loops.is_loop(node, key):  # see loops.py
                        loops.cut += 1
                        methods = ()
                for m, unify_head, branches, index in methods:
                    env = [None] * m.nvars
                    if not unify_head(task.args, env):
                        continue
                    for k, (sat, reduce, ordered) in enumerate(branches):
                        found = False
                        bindings = sat(env)
                        if threats is not None and m.name in self._threatening:
                            bindings = threats.order(bindings, reduce, state, root)
                        for nb in bindings:
                            node.subtasks = reduce(nb)
                            if needs is not None and needs.refused(node.subtasks, state, root):
                                node.subtasks = None
                                found = True  # the branch applied: no later one is tried
                                continue
                            node.ordered = ordered
                            node.how = (m, k, index)
                            if key is not None and node.subtasks:
                                assert loops is not None  # key: the loop check is on
                                loops.enter(node, key)
                            tried = True
                            yield node
                            self._cursor_ok = False
                            if len(trail) > mark:
                                undo_marks(trail, mark, loops)
                            if node.loop_key is not None:
                                assert loops is not None  # entered above: the loop check is on
                                loops.leave(node)
                            found = True
                            node.subtasks = None
                            node.how = None
                        if found:
                            break
            if not tried and explain is not None:
                explain.dead_end(self, node)
            self.stats.backtracks += 1

    def _first(self, chosen: Node, trail: list) -> list:
        """``first_tasks(chosen)``, resuming from the cursor when it is valid.

        The cursor is the path (``(list, index)`` pairs from the root) to the
        task the last walk found. Going forward, the network changes only at
        that task (it is applied, or reduced and then searched from), so the
        next walk from the root can resume there. Any backtracking may change
        the network anywhere above: every frame drops the cursor as soon as
        one of its ``yield`` returns.
        """
        cursor = self._cursor
        if chosen is self.root:
            if self._cursor_ok and cursor:
                found = first_in_order(chosen, trail, cursor, cursor.pop())
                if found is not None:
                    return found
            cursor.clear()
            found = first_tasks(chosen, trail, cursor)
            self._cursor_ok = bool(cursor)
            return found
        if self._cursor_ok and cursor and chosen.ordered:
            parent, i = cursor[-1]
            if parent.subtasks[i] is chosen:  # searching inside the task just reduced
                inner: list = []
                found = first_in_order(chosen, trail, inner)
                if found is not None:
                    cursor.extend(inner)
                    return found
        self._cursor_ok = False
        return first_tasks(chosen, trail)

    def goal_holds(self) -> bool:
        """Whether the problem's goal (HDDL) holds in the current state."""
        assert self._goal is not None  # asked only of a problem with a goal
        sat, nvars = self._goal
        return next(iter(sat([None] * nvars)), None) is not None

    # ------------------------------------------------------------ operators
    @classmethod
    def for_state(
        cls, domain: S.Domain, state, functions=None, goal=None, goal_nvars: int = 0
    ) -> Planner:
        """A planner with no tasks, used as the operator model of a world:
        its state is a copy of ``state`` (the atoms of an initial or an
        observed state), changed by :meth:`apply_step`. The executor's
        belief, the symbolic robot's world, plan repair's check and plan
        validation are such models; ``goal`` is an HDDL goal to test with
        :meth:`goal_holds`. No loop check: nothing is decomposed."""
        return cls(
            domain,
            S.ProblemInstance(state, S.TaskList([]), goal=goal, goal_nvars=goal_nvars),
            functions,
            loop_check=False,
        )

    def step_options(self, name: str, args: tuple):
        """``(operator, binding)`` for each way the ground step ``(name . args)``
        is applicable in the current state: operators in definition order,
        then satisfiers of the precondition in JSHOP2's order (lazily; the
        state must be as it was when the next option is asked for)."""
        for op, unify_head, pre, _bind, _cost in self._ops.get(name, ()):
            env = [None] * op.nvars
            if unify_head(tuple(args), env):
                for nb in pre(env):
                    yield op, nb

    def effects(self, op: S.Operator, env: list) -> tuple[list, list]:
        """The ground atoms ``(pred, args)`` an operator would delete and add
        under ``env``, evaluated in the current state (protections left out)."""
        return self.operators.effects(op, env)

    def apply(self, op: S.Operator, env: list) -> Change | None:
        """Apply an operator to the state (manual 5.2.1); the change, to undo
        it, or None (state unchanged) if it would delete a protected atom."""
        change, ok = self._apply(op, env)
        if ok:
            return change
        change.undo(self.state)
        return None

    def apply_step(self, name: str, args: tuple) -> bool:
        """Apply a ground plan step to this planner's state, as the search would.

        The step's operator must unify with it and its precondition hold; the
        first satisfier is used. Returns False (state unchanged) otherwise.
        Used to keep a belief state during execution and to check plans.
        """
        for op, env in self.step_options(name, args):
            if self.apply(op, env) is not None:
                return True
        return False
