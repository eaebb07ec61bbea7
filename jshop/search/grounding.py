"""Grounding an HDDL problem for the heuristic search (after PANDA's
grounder: Behnke et al., "On Succinct Groundings of HTN Planning
Problems", AAAI 2020, in a simpler form).

1. **Reachable facts**: the delete-relaxed fixpoint of the actions from the
   initial state (negative and universal conditions dropped), computed with
   the planner's own logic engine on a growing state.
2. **Top-down**: from the initial task network, each ground compound task
   is instantiated with every method whose relaxed precondition has a
   satisfier in the reachable facts (which binds every method parameter,
   HDDL's semantics), and each ground action with its head's binding.
3. **Bottom-up**: a ground action is kept if its precondition can hold in a
   reachable state; a ground compound task if some method has every
   subtask kept, to a fixpoint (PANDA's task decomposition graph pruning).
4. **Hierarchical reachability** (:mod:`.task_reach`), during step 2: the
   subtasks of the methods reached (with the facts the actions reached
   before can add) are instantiated first; where that proves a task of the
   initial network unreachable, the problem has no plan and grounding stops
   (see ``SKIPPED``), else the rest is instantiated as before.

What is left is numbered: dynamic facts are bits of an ``int`` state,
tasks and methods indices; preconditions are compiled residuals
(:mod:`htn.jshop.search.ground_formulas`). The pulled-up conditions of the
domain's methods (:mod:`htn.jshop.readers.pullup`) take part like written
ones: they only cut method instances that have no plan below them.
"""

from __future__ import annotations

from htn.jshop.language import syntax as S
from htn.jshop.language.terms import subst, variables
from htn.jshop.logic.caches import IdentityCache
from htn.jshop.logic.compile import head_unifier

from .ground_formulas import (
    COMPILE_AFTER,
    FormulaGrounder,
    NotGroundable,
    compile_residual,
    conj,
    disj,
    negate,
)
from .jshop2_input import checked_instance, flat_tasks
from .reachability import reachable
from .residual_code import compile_body
from .splitting import split_methods, totally_ordered
from .task_reach import Reach, reached

# step 4 runs on the part of the model the hierarchy reaches (to prove that
# there is no plan) where that part has at most SMALL methods or the tasks it
# left out are at least 1/SKIPPED of all: IPC 2020 Minecraft-Player
# p-006-006-006-006 leaves out 115k tasks of 148k, and on Woodworking 18's
# 147k methods it would cost 2 s for nothing. Where it finds a plan possible,
# the rest is ground as without it and the searches see the same model: one
# without what the hierarchy cannot reach made GBFS five times slower per
# node on Woodworking 14 and 17 (its relaxed composition then proves dead
# ends by settling whole passes)
SKIPPED = 3
SMALL = 20_000
# the goal of a model where grounding found it false in every reachable state
# (no fact has every bit: no state satisfies it)
UNREACHABLE_GOAL = (-1, -1, ())


class GroundAction:
    __slots__ = ("name", "args", "op", "pre", "dels", "adds", "effects", "cost")

    def __init__(self, name, args, op, pre, dels, adds, effects, cost):
        self.name, self.args, self.op = name, args, op
        self.pre = pre  # (pos, neg, rest)
        self.dels, self.adds = dels, adds  # masks
        self.effects = effects  # ((condition, dels, adds), ...) conditional
        self.cost = cost

    def possible_adds(self) -> int:
        """The facts some effect of the action may add (the mask), its
        conditional effects' as if their conditions held."""
        adds = self.adds
        for _cond, _dels, more in self.effects:
            adds |= more
        return adds


class GroundMethod:
    __slots__ = ("task", "method", "pre", "body", "order", "branch")

    def __init__(self, task, method, pre, body, order, branch=0):
        self.task = task  # the task id it decomposes
        self.method = method  # the S.Method
        self.pre = pre
        self.body = body  # subtask ids, in the method's (topological) order
        self.order = order  # True, False or a PartialOrder
        self.branch = branch  # the index of the method's branch (JSHOP2's if-then-else)


class GroundModel:
    """A grounded problem: facts, tasks (``tasks[i] = (name, args)``; an
    action's task id is its action index), methods per task, the initial
    state and task network, and the goal."""

    def __init__(self):
        self.facts: list = []  # bit -> (pred, args)
        self.bits: dict = {}
        self.tasks: list = []  # id -> (name, args)
        self.task_ids: dict = {}
        self.actions: dict = {}  # task id -> GroundAction (primitive tasks)
        self.methods_of: dict = {}  # task id -> [GroundMethod]
        self.init = 0
        self.roots: tuple = ()  # initial task ids
        self.root_order: object = True  # True, False or a PartialOrder
        self.goal: tuple | None = None  # (pos, neg, rest) or None
        self.hidden: frozenset = frozenset()  # the task names parameter splitting made

    def parents(self) -> dict:
        """Per task, the compound tasks with a method that has it as a
        subtask (the task decomposition graph, bottom up)."""
        out: dict = {}
        for t, ms in self.methods_of.items():
            for gm in ms:
                for s in gm.body:
                    out.setdefault(s, set()).add(t)
        return out

    def task_id(self, name: str, args: tuple) -> int:
        key = (name, args)
        i = self.task_ids.get(key)
        if i is None:
            i = self.task_ids[key] = len(self.tasks)
            self.tasks.append(key)
        return i


def ground(
    domain: S.Domain, instance: S.ProblemInstance, split: bool = True, reach: bool = True
) -> GroundModel:
    """The grounded problem (see the module docstring); raises
    :class:`NotGroundable` for what this search does not handle. ``split``:
    with parameter splitting (:mod:`.splitting`) where it applies; ``reach``:
    with step 4 (the tests compare)."""
    steps = grounding_steps(domain, instance, split, reach)
    while True:
        try:
            next(steps)
        except StopIteration as done:
            return done.value


def grounding_steps(
    domain: S.Domain, instance: S.ProblemInstance, split: bool = True, reach: bool = True
):
    """:func:`ground` as a generator that yields None between small steps
    (so that a portfolio can pause it) and returns the model."""
    return _Grounder(domain, instance, split, reach).run()


class _Grounder:
    def __init__(
        self, domain: S.Domain, instance: S.ProblemInstance, split: bool = True, reach: bool = True
    ):
        self.reach = reach
        if domain.language != "hddl":  # what of JSHOP2's language grounding takes, located
            instance = checked_instance(domain, instance)
        self.domain, self.instance = domain, instance
        self.model = GroundModel()
        self.dynamic = domain.dynamic_predicates()
        for ops in domain.operators.values():
            for op in ops:
                if type(op.cost) is not float:
                    raise NotGroundable(f"the cost of {op.name} is not a number")
                if op.add.var is not None or op.delete.var is not None:
                    raise NotGroundable(f"{op.name} has a variable effect list")
        self.methods = {name: list(ms) for name, ms in domain.methods.items()}
        self.roots, self.root_order = flat_tasks(instance.tasks)
        if instance.top is not None:
            m = S.root_method(instance)
            self.methods[m.name] = [m]
            self.roots, self.root_order = [m.head], True
        self.origin: dict = {}  # id(a split method) -> the method as written
        if split and totally_ordered(self.methods, self.root_order):
            # a derived predicate may change with the state: not static
            changing = self.dynamic | set(domain.axioms)
            self.methods, self.origin, self.model.hidden = split_methods(self.methods, changing)

    # ------------------------------------------------------------ 1. facts
    def reachable_facts(self):
        state, self.initial, self.logic = yield from reachable(self.domain, self.instance)
        self.logic.freeze()  # the reachable facts are final: atoms looked up, not scanned
        return state

    # ------------------------------------------------------------ 2. top down
    def run(self):
        model = self.model
        reach = yield from self.reachable_facts()
        static = {}
        for pred, lst in reach.atoms.items():
            if pred not in self.dynamic:
                static[pred] = set(lst)
        for pred, args in reach.facts():
            if pred in self.dynamic and None not in args:
                model.bits[(pred, args)] = len(model.facts)
                model.facts.append((pred, args))
        self.formulas = FormulaGrounder(static, model.bits, self.logic)
        for pred, args in self.initial:
            bit = model.bits.get((pred, args))
            if bit is not None:
                model.init |= 1 << bit
        roots = [model.task_id(t.name, tuple(t.args)) for t in self.roots]
        self.ops = {
            name: [(op, head_unifier(op.head.args)) for op in ops]
            for name, ops in self.domain.operators.items()
        }
        self.heads = {
            name: [(m, head_unifier(m.head.args)) for m in ms] for name, ms in self.methods.items()
        }
        self.executable: dict = {}  # (name, args) -> GroundAction or None
        self.head_bound: dict = {}
        self.bodies = IdentityCache(global_=False)  # branch -> see _body_code
        model.roots, model.root_order = tuple(roots), self.root_order
        seen = set(roots)
        r = Reach(model.init) if self.reach else None
        # a task the initial network names twice is grounded once
        yield from self._top_down(list(dict.fromkeys(roots)), seen, r)
        if r is not None:
            # what the hierarchy did not reach, grounded as before unless it
            # proves the problem has no plan (see SKIPPED)
            rest = []
            for ms in model.methods_of.values():
                for gm in ms:
                    for sub in gm.body:
                        if sub not in seen:
                            seen.add(sub)
                            rest.append(sub)
            methods = sum(len(ms) for ms in model.methods_of.values())
            check = methods <= SMALL or len(rest) * SKIPPED >= len(seen)
            if check and self._unreachable(r):
                return model
            yield from self._top_down(rest, seen, None)
        self._prune()
        if self.instance.goal is not None:
            goal = self._residual(self.instance.goal.expr, [None] * self.instance.goal_nvars)
            model.goal = compile_residual(goal) or UNREACHABLE_GOAL
        return model

    def _top_down(self, todo: list, seen: set, r: Reach | None):
        """Step 2 from ``todo``: each task's methods or action, then the
        subtasks of the methods ``r`` reaches (of every method without it)."""
        model = self.model
        while todo:
            for t in todo:
                yield
                name, args = model.tasks[t]
                if name.startswith("!"):
                    a = self.executable.get((name, args)) or self._action(name, args)
                    if a is not None:
                        model.actions[t] = a
                        if r is not None:
                            r.action(t, a)
                    continue
                found = model.methods_of[t] = []
                for m, unify in self.heads.get(name, ()):
                    found += self._methods(t, m, unify, args)
                if r is not None:
                    r.methods_of(t, found)
            subtasks = (
                r.take()
                if r is not None
                else [s for t in todo for gm in model.methods_of.get(t, ()) for s in gm.body]
            )
            todo = []
            for s in subtasks:
                if s not in seen:
                    seen.add(s)
                    todo.append(s)

    def _unreachable(self, r: Reach) -> bool:
        """Whether step 4 leaves a task of the initial network without a
        method: then the model is left so (no plan), else as it was."""
        model = self.model
        methods_of = {t: list(ms) for t, ms in model.methods_of.items()}
        actions = dict(model.actions)
        self._reach(r)
        if any(t not in self.alive for t in model.roots):
            return True
        model.methods_of, model.actions = methods_of, actions
        return False

    def _residual(self, expr, env: list):
        """The residual of a formula whose free variables the relaxed
        satisfiers bind (an ``exists``): the disjunction over them."""
        f = self.formulas
        return disj([f.ground(expr, nb) for nb in f.satisfiers(expr, env)])

    def _action(self, name: str, args: tuple):
        for op, unify in self.ops.get(name, ()):
            env: list = [None] * op.nvars
            if not unify(args, env):
                continue
            witness: list | None
            if self._bound_by_head(op):  # the common case: no exists to enumerate
                witness = env
                pre = compile_residual(self.formulas.ground(op.pre.expr, env))
            else:
                pre = compile_residual(self._residual(op.pre.expr, env))
                witness = next(self.formulas.satisfiers(op.pre.expr, env), None)
            if pre is None or witness is None:
                continue
            dels, adds, effects = self._effects(op, witness)
            return GroundAction(name, args, op, pre, dels, adds, effects, op.cost)
        return None

    def _bound_by_head(self, op: S.Operator) -> bool:
        """Whether the head binds every variable of the precondition outside
        its ``forall`` s (which the formula grounder expands itself)."""
        hit = self.head_bound.get(id(op))
        if hit is None:
            head = {v.index for v in variables(op.head.args, [])}
            hit = self.head_bound[id(op)] = _top_variables(op.pre.expr) <= head
        return hit

    def _effects(self, op: S.Operator, env: list):
        masks = [0, 0]
        effects = []
        bits = self.model.bits
        for k, eff in enumerate((op.delete, op.add)):
            for item in eff.items:
                if isinstance(item, S.Atom):
                    bit = bits.get((item.pred, subst(item.args, env)))
                    if bit is not None:
                        masks[k] |= 1 << bit
                    continue
                if not isinstance(item, S.EffectForAll):
                    raise NotGroundable(f"{op.name}: a protection in an HDDL action")
                for nb in self.formulas.satisfiers(item.cond, env):
                    cond = compile_residual(self.formulas.ground(item.cond, nb))
                    if cond is None:
                        continue
                    mask = 0
                    for a in item.atoms:
                        bit = bits.get((a.pred, subst(a.args, nb)))
                        if bit is not None:
                            mask |= 1 << bit
                    if cond == (0, 0, ()):
                        masks[k] |= mask
                    elif mask:
                        effects.append((cond, mask, 0) if k == 0 else (cond, 0, mask))
        return masks[0], masks[1], tuple(effects)

    def _methods(self, t: int, m: S.Method, unify, args: tuple):
        env = [None] * m.nvars
        if not unify(args, env):
            return
        earlier: list = []  # the residuals of the earlier branches' preconditions
        last = len(m.branches) - 1
        for k, branch in enumerate(m.branches):
            # JSHOP2's if-then-else: branch k applies where no earlier one does
            unless = negate(disj(earlier)) if earlier else True
            if unless is False:
                return
            yield from self._branch(t, m, k, env, unless)
            if k < last:
                earlier.append(self._residual(branch.pre.expr, env))

    def _branch(self, t: int, m: S.Method, k: int, env: list, unless):
        model = self.model
        branch = m.branches[k]
        code = self._body_code(branch)
        items, order = code[2], code[3]
        groups: dict = {}
        for nb in self.formulas.satisfiers(branch.pre.expr, env):
            residual = self.formulas.ground(branch.pre.expr, nb)
            if residual is False:
                continue
            make = code[1]
            body = None
            if make is not None:
                body = make(nb)
                if any(None in args for _, args in body):
                    body = None
            else:
                code[0] += 1
                if code[0] == COMPILE_AFTER:
                    code[1] = compile_body(items, getattr(m.head, "pos", None))
            if body is None:
                body = tuple((x.name, subst(x.args, nb)) for x in items)
            if body not in groups:
                if any(None in args for _, args in body):
                    raise NotGroundable(f"method {m.name}: a subtask argument no condition binds")
                # an action that can never apply kills the method at once, before
                # its compound subtasks are grounded (PANDA prunes them bottom-up)
                if not all(
                    self._executable(name, args) for name, args in body if name.startswith("!")
                ):
                    groups[body] = None
                    continue
                groups[body] = []
            if groups[body] is not None:
                groups[body].append(residual)
        for body, residuals in groups.items():
            if residuals is None:
                continue
            pre = disj(residuals)
            pre = compile_residual(pre if unless is True else conj([pre, unless]))
            if pre is not None:
                ids = tuple(model.task_id(name, args) for name, args in body)
                yield GroundMethod(t, self.origin.get(id(m), m), pre, ids, order, k)

    def _body_code(self, branch: S.Branch) -> list:
        """``[uses, compiled subtask list or None, subtasks, order]``: a
        branch's body (its nested lists flattened, :func:`flat_tasks`) is
        compiled (:func:`compile_body`) once it has been instantiated
        ``COMPILE_AFTER`` times, unless its arguments are not all variables
        and constants."""
        hit = self.bodies.get(branch)
        if hit is None:
            items, order = flat_tasks(branch.tasks)
            hit = self.bodies.put(branch, [0, None, items, order])
        return hit

    def _executable(self, name: str, args: tuple) -> bool:
        """Whether the ground action can apply in some reachable state (kept
        for the action's task, which the top-down pass reads later)."""
        key = (name, args)
        if key not in self.executable:
            self.executable[key] = self._action(name, args)
        return self.executable[key] is not None

    # ------------------------------------------------------------ 3. bottom up
    def _reach(self, r: Reach) -> None:
        """Step 4 after step 3: drop the methods and actions that the task
        hierarchy did not reach (``r``), prune, and again until pruning
        removes nothing: a method pruned can leave actions out of reach
        (Monroe-Fully-Observable pfile05: everything is reached before
        pruning, 56,983 of 63,747 methods after)."""
        model = self.model
        methods, actions = r.methods, r.actions
        while True:
            for t in [t for t in model.actions if t not in actions]:
                del model.actions[t]
            for ms in model.methods_of.values():
                if any(gm not in methods for gm in ms):
                    ms[:] = [gm for gm in ms if gm in methods]
            if not self._prune():
                return
            _facts, methods, actions = reached(model)

    def _prune(self) -> int:
        """The methods removed."""
        model = self.model
        alive = set(model.actions)
        changed = True
        while changed:
            changed = False
            for t, ms in model.methods_of.items():
                if t not in alive and any(all(s in alive for s in gm.body) for gm in ms):
                    alive.add(t)
                    changed = True
        removed = 0
        for t, ms in model.methods_of.items():
            n = len(ms)
            ms[:] = [gm for gm in ms if all(s in alive for s in gm.body)] if t in alive else []
            removed += n - len(ms)
        self.alive = alive
        return removed


def _top_variables(e) -> set:
    """The variable slots of a formula outside its ``forall`` s."""
    out: set = set()
    stack = [e]
    while stack:
        x = stack.pop()
        if isinstance(x, S.Atom):
            out.update(v.index for v in variables(x.args, []))
        elif isinstance(x, (S.And, S.Or)):
            stack.extend(x.items)
        elif isinstance(x, S.Not):
            stack.append(x.expr)
        elif isinstance(x, S.Equal):
            out.update(v.index for v in variables((x.left, x.right), []))
        elif not isinstance(x, S.ForAll):
            raise NotGroundable(f"{type(x).__name__} in a precondition")
    return out
