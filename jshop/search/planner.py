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
from typing import Iterator, Optional

from htn.jshop.language import syntax as S
from htn.jshop.language.errors import PlanningError
from htn.jshop.language.terms import subst, term_str, variables
from htn.jshop.logic.compile import head_unifier, substituter, task_list_maker
from htn.jshop.logic.engine import Logic
from htn.jshop.logic.operators import Operators
from htn.jshop.logic.state import Change, HashedState, State
from htn.jshop.plans.plan import Plan, Step
from htn.jshop.plans.tree import snapshot

from .goals import GoalGuard
from .limits import DEFAULT_MAX_DEPTH, MemoryGuard
from .loops import LoopCheck

_PLAN = object()


class Task:
    """A task instance in the network: a bound task atom."""
    __slots__ = ("name", "args", "immediate", "primitive", "src")

    def __init__(self, name, args, immediate, src=None):
        self.name = name
        self.args = args
        self.immediate = immediate
        self.primitive = name[0] == "!"
        self.src = src

    def __str__(self) -> str:
        from htn.jshop.language.terms import atom_str
        return atom_str(self.name, self.args)


class Node:
    """A task list in the network; atomic while ``subtasks`` is None.

    ``how`` records what reduced an atomic node (for the task tree): a
    ``(method, branch_index, method_index)`` triple or the plan step's index.
    """
    __slots__ = ("task", "subtasks", "ordered", "how", "done", "start", "loop_key")

    def __init__(self, task=None, subtasks=None, ordered=True):
        self.task = task
        self.subtasks = subtasks
        self.ordered = ordered
        self.how = None
        self.done = False   # cached: every task below is achieved
        self.start = 0      # cached: members before this index are achieved
        self.loop_key = None   # the active task instance it is, see loops.py


def compile_tasks(tl):
    """Compile a task list into ``env -> [Node]`` (its bound subtasks)."""
    return task_list_maker(tl, Node, Task)


def _bind_tasks(tl: S.TaskList, env: list) -> Node:
    """The node of a task list bound by ``env``, built directly: the
    problem's task list is bound once, and may be long (compiling it would
    cost more than it saves)."""
    return Node(None, [_bind_tasks(x, env) if isinstance(x, S.TaskList)
                       else Node(Task(x.name, subst(x.args, env), x.immediate, x))
                       for x in tl.items], tl.ordered)


def first_tasks(root: Node, trail: Optional[list] = None, path: Optional[list] = None) -> list:
    """JSHOP2's ``TaskList.getFirst``, without recursion.

    An ordered list contributes the first tasks of its first non-empty member;
    an unordered list those of every member; an immediate task, wherever it is
    met, is then the only option.

    With a ``trail``, what is found achieved is cached for later calls: a
    member with nothing left is marked ``done``, and a list's ``start`` moves
    past its achieved leading members. Each change is pushed on the trail; the
    planner undoes those made below a search frame when it backtracks into it.

    With a ``path`` (an empty list), an ordered network's walk leaves in it
    where the task found is (see :func:`_first_in_order`); it is emptied if
    the general way was taken.
    """
    if trail is not None and root.ordered:
        found = _first_in_order(root, trail, path)
        if found is not None:
            return found
    if path:
        path.clear()
    return _first_tasks(root, trail)


def _first_in_order(root: Node, trail: list, path: Optional[list] = None,
                    at: Optional[tuple] = None) -> Optional[list]:
    """:func:`first_tasks` while every list met is ordered (the common case,
    and all of HDDL): one walk down to the first task left; None when an
    unordered list is met (the caller then takes the general way).

    ``path`` is left holding the ``(list, index)`` of each ancestor of the
    task found, its own last. A later walk can resume from there (``at``, the
    task's own entry popped off ``path``) instead of walking down from the
    root again: the planner's cursor, which makes a long tail recursion
    linear rather than quadratic (see ``Planner._first``).
    """
    if path is None:
        path = []
    node, i = at if at is not None else (root, root.start)
    while True:
        subs = node.subtasks
        n = len(subs)
        while i < n:
            child = subs[i]
            cs = child.subtasks
            if cs is None:
                path.append((node, i))
                return [child]
            if cs and not child.done:
                if not child.ordered:
                    return None
                path.append((node, i))
                node, i = child, child.start
                break
            if i == node.start:
                trail.append((node, i))
                node.start = i + 1
            i += 1
        else:
            if not path:
                return []
            node.done = True
            trail.append(node)
            node, i = path.pop()
            i += 1


def _first_tasks(root: Node, trail: Optional[list]) -> list:
    res: list = []
    stack: list = []       # (list, next member, len(res) on entry) of each ancestor
    node, i, n0 = root, root.start, 0
    while True:
        subs = node.subtasks
        n = len(subs)
        down = False
        while i < n:
            child = subs[i]
            i += 1
            cs = child.subtasks
            if cs is None:
                if child.task.immediate:
                    return [child]
                res.append(child)
                if node.ordered:
                    break
            elif cs and not child.done:
                stack.append((node, i, n0))
                node, i, n0 = child, child.start, len(res)
                down = True
                break
            elif trail is not None and i - 1 == node.start:
                trail.append((node, i - 1))
                node.start = i
        if down:
            continue
        # ``node`` is finished: exhausted, or ordered and it gave a task
        while True:
            if trail is not None and len(res) == n0 and stack:
                node.done = True
                trail.append(node)
            if not stack:
                return res
            node, i, n0 = stack.pop()
            if not (node.ordered and len(res) != n0):
                break


def _undo_marks(trail: list, mark: int, loops=None) -> None:
    """Forget what :func:`first_tasks` cached since ``mark``."""
    while len(trail) > mark:
        entry = trail.pop()
        if type(entry) is tuple:
            entry[0].start = entry[1]
        else:
            entry.done = False
            if loops is not None:
                loops.reopened(entry)


def compat_warning(domain: S.Domain):
    """The one warning ``--jshop2-compat`` gives for a domain whose method
    bodies are written ``(:unordered ...)`` (they will run in order), or None."""
    from htn.jshop.readers.checks import Warning_
    bodies = [b for ms in domain.methods.values() for m in ms for b in m.branches
              if not b.tasks.ordered]
    if not bodies:
        return None
    more = f" (and {len(bodies) - 1} more)" if len(bodies) > 1 else ""
    return Warning_(bodies[0].tasks.pos or bodies[0].pos,
                    f"--jshop2-compat: this (:unordered ...) method body{more} runs in "
                    "order, as in JSHOP2 1.0.3; without the option it is unordered")


def _deepest_task(root: Node, req: Node) -> Optional[Task]:
    """The task to name when the search is too deep: the one just reduced, or
    else the deepest reduced compound task of the network."""
    if req.task is not None and not req.task.primitive:
        return req.task
    best, best_depth = None, -1
    stack = [(root, 0)]
    while stack:
        node, depth = stack.pop()
        if node.task is not None and node.subtasks is not None and not node.task.primitive:
            depth += 1
            if depth > best_depth:
                best, best_depth = node.task, depth
        for child in node.subtasks or ():
            stack.append((child, depth))
    return best


class Stats:
    __slots__ = ("plans_found", "expansions", "operator_applications",
                 "backtracks", "started", "elapsed", "timed_out", "interrupted",
                 "bound")

    def __init__(self):
        self.plans_found = 0
        self.expansions = 0
        self.operator_applications = 0
        self.backtracks = 0
        self.started = 0.0
        self.elapsed = 0.0
        self.timed_out = False
        self.interrupted = False
        self.bound = None      # the SearchBound (depth or memory) that stopped the search

    def as_dict(self) -> dict:
        return {
            "plans_found": self.plans_found,
            "search_ms": round(self.elapsed * 1000, 3),
            "expansions": self.expansions,
            "operator_applications": self.operator_applications,
            "backtracks": self.backtracks,
            "timed_out": self.timed_out,
            "interrupted": self.interrupted,
            "depth_limit_reached": isinstance(self.bound, DepthLimit),
            "memory_limit_reached": isinstance(self.bound, MemoryLimit),
        }


class SearchBound:
    """A bound that stopped the search, and the task being reduced deepest."""
    __slots__ = ("limit", "task")

    def __init__(self, limit: int, task: Optional[Task]):
        self.limit = limit
        self.task = task

    def __str__(self) -> str:
        if self.task is None:
            return self.message(None)
        pos = getattr(self.task.src, "pos", None)
        return (f"{pos}: " if pos else "") + self.message(self.task)

    def message(self, task) -> str:
        raise NotImplementedError


class DepthLimit(SearchBound):
    """The search stopped at ``max_depth`` nested reductions without a step."""
    __slots__ = ()

    def message(self, task) -> str:
        what = (f"task {task} recurses past the search depth limit" if task is not None
                else "the search reached its depth limit")
        return (f"{what} ({self.limit:,} nested reductions without a step); "
                "search stopped (raise it with --max-depth N)")


class MemoryLimit(SearchBound):
    """Why the search stopped at its memory budget: the plan on the current
    path needs more memory than the budget, or the search never ends."""
    __slots__ = ()

    def message(self, task) -> str:
        at = f" at task {task}" if task is not None else ""
        return (f"the search used its memory budget ({self.limit >> 20:,} MB){at}; "
                "search stopped (raise it with --max-memory MB)")


class Planner:
    """Finds plans for one problem instance of a domain."""

    def __init__(self, domain: S.Domain, instance: S.ProblemInstance,
                 functions=None, record_trees: bool = False,
                 jshop2_compat: bool = False, max_depth: int = DEFAULT_MAX_DEPTH,
                 loop_check: Optional[bool] = None, explain=None,
                 max_memory: Optional[int] = None, tree_paths: bool = True):
        self.domain = domain
        self.explain = explain      # an explain.Explainer collecting dead ends, or None
        self.instance = instance
        self.record_trees = record_trees
        self.tree_paths = tree_paths     # node paths in recorded trees (see tree.snapshot)
        self.max_depth = max_depth
        self.max_memory = max_memory     # bytes, or None for the default budget
        if loop_check is None:           # on for HDDL, off for JSHOP2 (its own semantics)
            loop_check = domain.language == "hddl"
        self.state = HashedState() if loop_check else State()
        self.loops = LoopCheck(self.state) if loop_check else None
        implied = domain.implied
        for atom in (*domain.facts, *instance.state):
            self.state.add(atom.pred, atom.args)
            for pred in implied.get(atom.pred, ()):    # HDDL supertypes
                self.state.add(pred, atom.args)
        self.logic = Logic(domain, self.state, functions)
        self.operators = Operators(self.state, self.logic)
        self._apply = self.operators.apply
        self._goal = self.guard = None
        if instance.goal is not None:
            self._goal = (self.logic.precondition(instance.goal), instance.goal_nvars)
            self.guard = GoalGuard(domain, instance.goal) or None
        pre = self.logic.precondition
        # (operator, head unifier, precondition, head substituter, constant cost or None)
        self._ops = {name: [(op, head_unifier(op.head.args), pre(op.pre, op.head.args),
                             substituter(op.head.args),
                             op.cost if type(op.cost) is float else None)
                            for op in ops]
                     for name, ops in domain.operators.items()}
        # (precondition, body, body is ordered) per branch; see the module docstring
        self._methods = {name: [(m, head_unifier(m.head.args),
                                 [(pre(b.pre, m.head.args), compile_tasks(b.tasks),
                                   jshop2_compat or b.tasks.ordered) for b in m.branches])
                                for m in ms]
                         for name, ms in domain.methods.items()}
        self.stats = Stats()
        # the problem's own variables (if any) stay unbound, like a method's
        nvars = 1 + max((v.index for t in S.task_atoms(instance.tasks)
                         for v in variables(t.args, [])), default=-1)
        if instance.top is not None:     # HDDL: a root task binds the network's parameters
            from htn.jshop.readers.hddl_domain import top_method
            m = top_method(domain, instance.top)
            self._methods[m.name] = [(m, head_unifier(m.head.args),
                                      [(pre(b.pre, m.head.args), compile_tasks(b.tasks), True)
                                       for b in m.branches])]
            self.root = _bind_tasks(S.TaskList([m.head]), [])
        else:
            self.root = _bind_tasks(instance.tasks, [None] * nvars)
        self._steps: list = []
        self._cost = 0.0
        self._trail: list = []     # nodes marked done, see first_tasks
        self._cursor: list = []    # where the last walk found its task, see _first
        self._cursor_ok = False

    # ------------------------------------------------------------ driver
    def plans(self, timeout: Optional[float] = None) -> Iterator[Plan]:
        """Stream plans in JSHOP2's order until exhausted or ``timeout``.

        ``stats.elapsed`` counts search time only, not the time the consumer
        spends between plans; ``timeout`` is wall-clock time since the start.
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
        t0 = stats.started = clock()
        spent = 0.0
        frame = self._frame
        root = self.root
        stack = [frame(root)]
        depths = [0]       # per frame: reductions since the last step on its path
        push, pop, nxt = stack.append, stack.pop, next
        dpush, dpop = depths.append, depths.pop
        max_depth = self.max_depth
        guard = None       # made at the first check: tiny searches never pay for it
        ticks = stats.expansions
        stats.expansions += 1
        try:
            while stack:
                req = nxt(stack[-1], None)     # frames never yield None
                if req is None:
                    pop()
                    dpop()
                    continue
                if req is _PLAN:
                    stats.plans_found += 1
                    plan = Plan([Step(*s) for s in self._steps], self._cost,
                                index=stats.plans_found - 1)
                    if self.record_trees:
                        plan.tree = snapshot(self.root, plan.steps, self.tree_paths)
                    spent += clock() - t0
                    stats.elapsed = spent
                    stats.expansions = ticks + 1
                    t0 = None          # the consumer's time is not search time
                    if gc_was_enabled:
                        gc.enable()
                    yield plan
                    gc.disable()
                    t0 = clock()
                    continue
                if req is root:         # an operator was applied (or a task list ended)
                    depth = 0
                else:
                    depth = depths[-1] + 1
                    if depth >= max_depth:
                        stats.bound = DepthLimit(max_depth, _deepest_task(root, req))
                        return
                push(frame(req))
                dpush(depth)
                ticks += 1
                if not ticks & 255:
                    if timeout is not None and clock() - stats.started > timeout:
                        stats.timed_out = True       # wall clock, output included
                        return
                    if not ticks & 4095:
                        if guard is None:
                            guard = MemoryGuard(self.max_memory)
                        if guard.exceeded():
                            stats.bound = MemoryLimit(guard.limit_bytes, _deepest_task(root, req))
                            return
        except KeyboardInterrupt:
            stats.interrupted = True
            raise
        finally:
            stats.elapsed = spent + (clock() - t0 if t0 is not None else 0.0)
            stats.expansions = ticks + 1
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
            tried = False        # did any operator or method apply?
            if task.primitive:
                node.subtasks = []
                steps, apply, guard = self._steps, self._apply, self.guard
                for op, unify_head, pre, bind_head, cost in self._ops.get(task.name, ()):
                    env = [None] * op.nvars
                    if not unify_head(task.args, env):
                        continue
                    for nb in pre(env):
                        change, ok = apply(op, nb)
                        if ok and guard is not None and guard.broken(
                                change, state, root, self._cursor if self._cursor_ok else None):
                            ok = False
                        if ok:
                            self.stats.operator_applications += 1
                            if cost is None:       # a cost term: evaluate it
                                cost = subst(op.cost, nb)
                                if type(cost) is not float:
                                    raise PlanningError.at(op.pos, f"cost of {op.name} is "
                                                           f"{term_str(cost)}, not a number")
                            node.how = len(steps)
                            steps.append((op.name, bind_head(nb), cost))
                            self._cost += cost
                            tried = True
                            yield root
                            self._cursor_ok = False
                            if len(trail) > mark:
                                _undo_marks(trail, mark, loops)
                            steps.pop()
                            self._cost -= cost
                            if type(op.cost) is not float:
                                cost = None
                        change.undo(state)
                node.subtasks = None
                node.how = None
            else:
                methods = self._methods.get(task.name, ())
                key = None
                if loops is not None:
                    key = loops.key(task)
                    if key in loops.active:     # see loops.py
                        loops.cut += 1
                        methods = ()
                for index, (m, unify_head, branches) in enumerate(methods):
                    env = [None] * m.nvars
                    if not unify_head(task.args, env):
                        continue
                    for k, (sat, reduce, ordered) in enumerate(branches):
                        found = False
                        for nb in sat(env):
                            node.subtasks = reduce(nb)
                            node.ordered = ordered
                            node.how = (m, k, index)
                            if key is not None and node.subtasks:
                                loops.enter(node, key)
                            tried = True
                            yield node
                            self._cursor_ok = False
                            if len(trail) > mark:
                                _undo_marks(trail, mark, loops)
                            if node.loop_key is not None:
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
                found = _first_in_order(chosen, trail, cursor, cursor.pop())
                if found is not None:
                    return found
            cursor.clear()
            found = first_tasks(chosen, trail, cursor)
            self._cursor_ok = bool(cursor)
            return found
        if self._cursor_ok and cursor and chosen.ordered:
            parent, i = cursor[-1]
            if parent.subtasks[i] is chosen:     # searching inside the task just reduced
                inner: list = []
                found = _first_in_order(chosen, trail, inner)
                if found is not None:
                    cursor.extend(inner)
                    return found
        self._cursor_ok = False
        return first_tasks(chosen, trail)

    def goal_holds(self) -> bool:
        """Whether the problem's goal (HDDL) holds in the current state."""
        sat, nvars = self._goal
        return next(iter(sat([None] * nvars)), None) is not None

    # ------------------------------------------------------------ operators
    @classmethod
    def for_state(cls, domain: S.Domain, state, functions=None, goal=None,
                  goal_nvars: int = 0) -> "Planner":
        """A planner with no tasks, used as the operator model of a world:
        its state is a copy of ``state`` (the atoms of an initial or an
        observed state), changed by :meth:`apply_step`. The executor's
        belief, the symbolic robot's world, plan repair's check and plan
        validation are such models; ``goal`` is an HDDL goal to test with
        :meth:`goal_holds`. No loop check: nothing is decomposed."""
        return cls(domain, S.ProblemInstance(state, S.TaskList([]), goal=goal,
                                             goal_nvars=goal_nvars),
                   functions, loop_check=False)

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

    def apply(self, op: S.Operator, env: list) -> Optional[Change]:
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
