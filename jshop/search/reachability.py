"""The facts an HDDL problem can reach under the delete relaxation: the
first step of grounding (:mod:`.grounding`).

Every action is applied, negative and universal conditions dropped, until
no new fact appears, with the planner's own logic engine on a growing
state. The fixpoint is semi-naive: after an action's first turn, only its
bindings that use a fact new since its last turn are enumerated, by binding
one of its precondition's atoms to each new fact in turn (a binding that
uses old facts only was found before). Where that does not hold (derived
predicates; a disjunction or a conditional effect reading a predicate that
has gained facts) the action's bindings are all enumerated again. Bindings
that agree on the parameters the added atoms read add the same facts, so
an action adds them for the first such binding only (Woodworking's
grinding reads a part's surface, colour and treatment and adds others:
instance 18's 241,920 bindings of it have 15 keys, one per part, and its
fixpoint takes 2.8 s instead of 10.4 s).
"""

from __future__ import annotations

from itertools import product

from htn.jshop.language import syntax as S
from htn.jshop.language.terms import Var, subst, variables
from htn.jshop.logic.compile import head_unifier
from htn.jshop.logic.engine import Logic
from htn.jshop.logic.state import State

from .ground_formulas import flat_and, mentions, relax


class _Program:
    """One action's relaxed precondition, compiled, and what it adds.

    A parameter that the relaxed precondition only types (Woodworking's
    actions take a colour and a treatment that only their effects name) is
    left out of the bindings: each added atom takes every object of its
    type on its own, so such parameters add their objects' counts to the
    facts instead of multiplying the bindings (Woodworking 07: 2.5 M
    bindings before). The facts reached are the same (``factor=False``
    binds them all, as the tests compare)."""

    def __init__(
        self, op: S.Operator, logic: Logic, every: bool, factor: bool = True, once: bool = True
    ):
        # a parameter of type object has no type condition: bind it too
        typed = [S.Atom("type:object", (v,)) for v in op.head.args if type(v) is Var]
        items = flat_and([relax(op.pre.expr), *typed]).items
        raw = [item for item in op.add.items if isinstance(item, S.EffectForAll)]
        self.types = _only_typed(op, items, raw) if factor else {}
        pre = S.And([x for x in items if not _types_of(x, self.types)])
        self.nvars = op.nvars
        self.sat = logic.precondition(S.Precondition(pre), op.head.args)
        self.state = logic.state
        self.objects: dict | None = None  # variable index -> objects of its types, once asked
        self.adds = [(item.pred, item.args) for item in op.add.items if isinstance(item, S.Atom)]
        self.foralls = [(logic.expr(flat_and([relax(item.cond)])), item.atoms) for item in raw]
        # the atoms a new fact can be bound to (and their unifiers); what else reads the state
        self.atoms = [(x.pred, head_unifier(x.args)) for x in pre.items if isinstance(x, S.Atom)]
        others = [x for x in pre.items if not isinstance(x, S.Atom)]
        self.reads = None if every else predicates([op.pre.expr, *(i.cond for i in raw)])
        self.others = predicates(others + [i.cond for i in raw])
        self.seen = -1  # the log's length at this action's last turn
        # the parameters the added atoms read: bindings that agree on them add
        # the same facts (None where a conditional effect reads the binding;
        # call terms, which could read more, are refused before grounding)
        self.key: list | None = None
        if once and not self.foralls:
            read = {v.index for _p, args in self.adds for v in variables(args, [])}
            self.key = sorted(read - set(self.types))
        self.done: set = set()  # the keys added already

    def bindings(self, log: list):
        """The bindings to apply now, given the facts added so far (``log``)."""
        new = log[self.seen :] if self.seen >= 0 else None
        self.seen = len(log)
        if new is None or self.reads is None:
            yield from self.sat([None] * self.nvars)
            return
        preds = {p for p, _ in new}
        if not preds & self.reads:
            return
        if preds & self.others:
            yield from self.sat([None] * self.nvars)
            return
        for wanted, unify in self.atoms:
            if wanted not in preds:
                continue
            for pred, args in new:
                if pred != wanted:
                    continue
                env = [None] * self.nvars
                if unify(args, env):
                    yield from self.sat(env)

    def added(self, env: list) -> list:
        if self.key is not None:
            key = tuple([env[i] for i in self.key])
            if key in self.done:
                return []
            self.done.add(key)
        if not self.types:
            out = [(pred, subst(args, env)) for pred, args in self.adds]
        else:
            out = []
            objects = self._objects()
            if not all(objects.values()):
                return out  # a parameter's type has no object: never applicable
            for pred, args in self.adds:
                mine = sorted({a.index for a in args if type(a) is Var and a.index in objects})
                if not mine:
                    out.append((pred, subst(args, env)))
                    continue
                full = list(env)
                for values in product(*(objects[i] for i in mine)):
                    for i, value in zip(mine, values):
                        full[i] = value
                    out.append((pred, subst(args, full)))
        for cond, atoms in self.foralls:
            for nb in cond(list(env)):
                out.extend((a.pred, subst(a.args, nb)) for a in atoms)
        return out

    def _objects(self) -> dict:
        """Per only-typed parameter, the objects of all its types (type
        atoms are static: asked once)."""
        if self.objects is None:
            self.objects = {}
            for index, preds in self.types.items():
                sets = [{args[0] for args in self.state.bucket(pred)} for pred in preds]
                self.objects[index] = sorted(set.intersection(*sets))
        return self.objects


def _only_typed(op: S.Operator, items: list, foralls: list) -> dict:
    """Parameter index -> its type predicates, for the parameters that the
    relaxed precondition ``items`` only types and no conditional effect reads."""
    types: dict = {}
    rest = []
    for x in items:
        if (
            isinstance(x, S.Atom)
            and x.pred.startswith("type:")
            and len(x.args) == 1
            and type(x.args[0]) is Var
        ):
            types.setdefault(x.args[0].index, []).append(x.pred)
        else:
            rest.append(x)
    rest += [y for item in foralls for y in (item.cond, *item.atoms)]
    params = {v.index for v in op.head.args if type(v) is Var}
    return {
        i: preds
        for i, preds in types.items()
        if i in params and not any(mentions(x, {i}) for x in rest)
    }


def _types_of(x, types: dict) -> bool:
    """Whether ``x`` is a type atom of an only-typed parameter."""
    return (
        isinstance(x, S.Atom)
        and x.pred.startswith("type:")
        and len(x.args) == 1
        and type(x.args[0]) is Var
        and x.args[0].index in types
    )


def reachable(
    domain: S.Domain,
    instance: S.ProblemInstance,
    semi_naive: bool = True,
    factor: bool = True,
    once: bool = True,
):
    """A generator (it yields between actions' turns, for the caller's
    deadline) that returns ``(state, initial facts, logic)``: the reachable
    facts, the initial state's, and the engine on the growing state.
    ``semi_naive=False`` enumerates every binding at every turn (the
    reference the tests compare with); ``factor=False`` binds every
    parameter, as :class:`_Program` says; ``once=False`` adds the facts of
    every binding (the module docstring)."""
    state = State()
    implied = domain.implied
    for atom in (*domain.facts, *instance.state):
        state.add(atom.pred, atom.args)
        for pred in implied.get(atom.pred, ()):
            state.add(pred, atom.args)
    initial = [(p, a) for p, a in state.facts()]
    logic = Logic(domain, state)
    logic.hot = True  # few calls, each a join over the growing facts: compiled at once
    every = bool(domain.axioms)  # a derived predicate could depend on any
    programs = [
        _Program(op, logic, every, factor, once) for ops in domain.operators.values() for op in ops
    ]
    log: list = []  # the facts added, in order
    changed = True
    while changed:
        changed = False
        for program in programs:
            yield
            if not semi_naive:
                program.seen = -1
            new = [fact for env in program.bindings(log) for fact in program.added(env)]
            for pred, args in new:
                if state.add(pred, args):
                    log.append((pred, args))
                    changed = True
    return state, initial, logic


def predicates(exprs: list) -> set:
    """The predicates the delete relaxations of ``exprs`` read."""
    out, stack = set(), [relax(e) for e in exprs]
    while stack:
        e = stack.pop()
        if isinstance(e, S.Atom):
            out.add(e.pred)
        elif isinstance(e, (S.And, S.Or)):
            stack.extend(e.items)
    return out
