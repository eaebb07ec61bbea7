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

Deliberately kept JSHOP2 1.0.3 behaviour: when a method reduces a task, only
the subtasks of the method's task list replace the task; the task keeps its
"ordered" flag, so a method body written ``(:unordered ...)`` at top level is
ordered (nested ``:unordered`` lists keep their meaning).
"""
from __future__ import annotations

import time
from typing import Iterator, Optional

from . import syntax as S
from .errors import PlanningError
from .logic import Logic, atom_from_term
from .plan import Plan, Step
from .state import Change, State
from .terms import Var, subst, term_str, unify
from .tree import TaskTree, snapshot

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
        from .terms import atom_str
        return atom_str(self.name, self.args)


class Node:
    """A task list in the network; atomic while ``subtasks`` is None.

    ``how`` records what reduced an atomic node (for the task tree): a
    ``(method, branch_index)`` pair or the index of the plan step.
    """
    __slots__ = ("task", "subtasks", "ordered", "how")

    def __init__(self, task=None, subtasks=None, ordered=True):
        self.task = task
        self.subtasks = subtasks
        self.ordered = ordered
        self.how = None


def instantiate(tl, env: list) -> Node:
    """Bind a task list of the domain (``TaskList.bind`` in JSHOP2)."""
    if isinstance(tl, S.TaskAtom):
        return Node(Task(tl.name, subst(tl.args, env), tl.immediate, tl))
    return Node(None, [instantiate(x, env) for x in tl.items], tl.ordered)


def first_tasks(root: Node) -> list:
    """JSHOP2's ``TaskList.getFirst``, without recursion.

    An ordered list contributes the first tasks of its first non-empty member;
    an unordered list those of every member; an immediate task, wherever it is
    met, is then the only option.
    """
    res: list = []
    stack = [[root, 0, 0]]          # node, next member, len(res) on entry
    while stack:
        frame = stack[-1]
        node, i, n0 = frame
        if i == 0:
            frame[2] = n0 = len(res)
        elif node.ordered and len(res) != n0:
            stack.pop()
            continue
        subs = node.subtasks
        if i == len(subs):
            stack.pop()
            continue
        child = subs[i]
        frame[1] = i + 1
        if child.subtasks is None:
            if child.task.immediate:
                return [child]
            res.append(child)
            if node.ordered:
                stack.pop()
        elif child.subtasks:
            stack.append([child, 0, 0])
    return res


class Stats:
    __slots__ = ("plans_found", "expansions", "operator_applications",
                 "backtracks", "started", "elapsed", "timed_out", "interrupted")

    def __init__(self):
        self.plans_found = 0
        self.expansions = 0
        self.operator_applications = 0
        self.backtracks = 0
        self.started = 0.0
        self.elapsed = 0.0
        self.timed_out = False
        self.interrupted = False

    def as_dict(self) -> dict:
        return {
            "plans_found": self.plans_found,
            "search_ms": round(self.elapsed * 1000, 3),
            "expansions": self.expansions,
            "operator_applications": self.operator_applications,
            "backtracks": self.backtracks,
            "timed_out": self.timed_out,
            "interrupted": self.interrupted,
        }


class Planner:
    """Finds plans for one problem instance of a domain."""

    def __init__(self, domain: S.Domain, instance: S.ProblemInstance,
                 functions=None, record_trees: bool = False):
        self.domain = domain
        self.instance = instance
        self.record_trees = record_trees
        self.state = State()
        for atom in instance.state:
            self.state.add(atom.pred, atom.args)
        self.logic = Logic(domain, self.state, functions)
        self._ops = {name: [(op, self.logic.precondition(op.pre)) for op in ops]
                     for name, ops in domain.operators.items()}
        self._methods = {name: [(m, [self.logic.precondition(b.pre) for b in m.branches])
                                for m in ms]
                         for name, ms in domain.methods.items()}
        self.stats = Stats()
        self.root = instantiate(instance.tasks, [])
        self._steps: list = []
        self._cost = 0.0
        self._forall_cache: dict = {}

    # ------------------------------------------------------------ driver
    def plans(self, timeout: Optional[float] = None) -> Iterator[Plan]:
        """Stream plans in JSHOP2's order until exhausted or ``timeout``.

        ``stats.elapsed`` counts search time only, not the time the consumer
        spends between plans; ``timeout`` is measured the same way.
        """
        stats = self.stats
        clock = time.perf_counter
        t0 = stats.started = clock()
        spent = 0.0
        stack = [self._frame(self.root)]
        push, pop = stack.append, stack.pop
        ticks = 0
        try:
            while stack:
                try:
                    req = next(stack[-1])
                except StopIteration:
                    pop()
                    continue
                if req is _PLAN:
                    stats.plans_found += 1
                    plan = Plan([Step(*s) for s in self._steps], self._cost,
                                index=stats.plans_found - 1)
                    if self.record_trees:
                        plan.tree = snapshot(self.root, plan.steps)
                    spent += clock() - t0
                    stats.elapsed = spent
                    t0 = None          # the consumer's time is not search time
                    yield plan
                    t0 = clock()
                    continue
                push(self._frame(req))
                ticks += 1
                if timeout is not None and not ticks & 255:
                    if spent + clock() - t0 > timeout:
                        stats.timed_out = True
                        return
        except KeyboardInterrupt:
            stats.interrupted = True
            raise
        finally:
            stats.elapsed = spent + (clock() - t0 if t0 is not None else 0.0)
            for frame in reversed(stack):
                frame.close()

    # ------------------------------------------------------------ one frame
    def _frame(self, chosen: Node):
        """One call of JSHOP2's ``findPlanHelper(chosen)``, as a generator.

        It yields a node to recurse into (the driver runs that call and then
        resumes this one) or ``_PLAN`` when the whole network is achieved.
        """
        self.stats.expansions += 1
        options = first_tasks(chosen)
        if not options:
            if chosen is not self.root:
                yield self.root
            else:
                yield _PLAN
            return
        state = self.state
        for node in options:
            task = node.task
            if task.primitive:
                node.subtasks = []
                for op, pre in self._ops.get(task.name, ()):
                    env = [None] * op.nvars
                    if not _unify_args(op.head.args, task.args, env):
                        continue
                    for nb in pre(env):
                        change, ok = self._apply(op, nb)
                        if ok:
                            self.stats.operator_applications += 1
                            cost = subst(op.cost, nb)
                            if type(cost) is not float:
                                raise PlanningError.at(op.pos, f"cost of {op.name} is "
                                                       f"{term_str(cost)}, not a number")
                            node.how = len(self._steps)
                            self._steps.append((op.name, subst(op.head.args, nb), cost))
                            self._cost += cost
                            yield self.root
                            self._steps.pop()
                            self._cost -= cost
                        change.undo(state)
                node.subtasks = None
                node.how = None
            else:
                for m, branches in self._methods.get(task.name, ()):
                    env = [None] * m.nvars
                    if not _unify_args(m.head.args, task.args, env):
                        continue
                    for k, sat in enumerate(branches):
                        found = False
                        for nb in sat(env):
                            node.subtasks = instantiate(m.branches[k].tasks, nb).subtasks
                            node.how = (m, k)
                            yield node
                            found = True
                            node.subtasks = None
                            node.how = None
                        if found:
                            break
            self.stats.backtracks += 1

    # ------------------------------------------------------------ operators
    def _apply(self, op: S.Operator, env: list):
        """Apply an operator (manual 5.2.1); False if it deletes a protected atom."""
        change = Change()
        state = self.state
        for pred, args in self._effect_atoms(op.delete, env, op):
            if pred is None:  # a protection condition to cancel
                p, a = args
                if state.unprotect(p, a):
                    change.unprotected.append((p, a))
                continue
            if state.is_protected(pred, args):
                return change, False
            i = state.delete(pred, args)
            if i != -1:
                change.deleted.append((pred, args, i))
        for pred, args in self._effect_atoms(op.add, env, op):
            if pred is None:
                p, a = args
                state.protect(p, a)
                change.protected.append((p, a))
                continue
            if state.add(pred, args):
                change.added.append((pred, args))
        return change, True

    def _effect_atoms(self, eff: S.Effects, env: list, op):
        """Ground atoms of a delete/add list; protections come as (None, atom).

        Generated lazily: a forall element's condition is evaluated while the
        atoms before it are already deleted, as in JSHOP2.
        """
        if eff.var is not None:
            lst = env[eff.var.index]
            if type(lst) is not tuple:
                raise PlanningError.at(op.pos, f"the effect list variable {eff.var.name} "
                                       f"of {op.name} is bound to {term_str(lst)}")
            for t in lst:
                yield atom_from_term(t, op.pos)
            return
        for item in eff.items:
            if isinstance(item, S.Atom):
                yield item.pred, subst(item.args, env)
            elif isinstance(item, S.VarAtom):
                yield self._var_atom(item, env)
            elif isinstance(item, S.Protection):
                yield None, self._ground(item.atom, env)
            else:  # EffectForAll
                cond = self._forall_sat(item)
                for nb in cond(env):
                    for a in item.atoms:
                        yield self._ground(a, nb)

    def _ground(self, a, env):
        if isinstance(a, S.VarAtom):
            return self._var_atom(a, env)
        return a.pred, subst(a.args, env)

    def _var_atom(self, a: S.VarAtom, env):
        t = env[a.var.index]
        if t is None:
            raise PlanningError.at(a.pos, f"effect variable {a.var.name} is not bound")
        return atom_from_term(t, a.pos)

    def _forall_sat(self, item: S.EffectForAll):
        sat = self._forall_cache.get(id(item))
        if sat is None:
            sat = self._forall_cache[id(item)] = self.logic.expr(item.cond)
        return sat


def _unify_args(pattern: tuple, args: tuple, env: list) -> bool:
    if len(pattern) != len(args):
        return False
    for p, t in zip(pattern, args):
        if not unify(p, t, env):
            return False
    return True


def find_plans(domain: S.Domain, problem: S.Problem, functions=None, limit: Optional[int] = 1,
               timeout: Optional[float] = None, record_trees: bool = False):
    """Convenience: plans of every instance of a problem, ``limit`` per instance."""
    out = []
    for inst in problem.instances:
        planner = Planner(domain, inst, functions, record_trees)
        for plan in planner.plans(timeout):
            out.append(plan)
            if limit is not None and len([p for p in out]) >= limit:
                break
    return out
