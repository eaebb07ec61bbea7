"""Conjunctions compiled once per binding mode (the search's hottest code).

JSHOP2 compiles every precondition into Java classes (manual section 4); a
conjunction there is a chain of objects, one per conjunct, each asked for its
next satisfier. :func:`htn.jshop.logic.compile.conjunction` does the same with one
generator per conjunct, which costs a generator, a binding tuple and a copy of
the binding for every conjunct of every satisfier. On small searches that
fixed cost is most of the time.

Here a conjunction is compiled again for each *binding mode* it is entered
with (which of its variables are bound, as Prolog compilers do): under a
known mode every conjunct's role is fixed, so the conjunction becomes one
generator of nested loops over Python locals. A conjunct with every variable
bound is a set lookup (``if (x1, x2) in members``); one with free variables
is a loop over the predicate's live list of atoms that binds locals; a call
is evaluated inline; the binding list is copied once, when a satisfier is
yielded; a flat list argument (``(goal (on ?x ?z))``) is matched element by
element in the same loop. Anything else (axioms, ``or``, ``forall``, list
terms nested deeper, a variable bound to a term with variables in it) is
asked of the general engine (:class:`htn.jshop.logic.engine.Logic`) from inside
the loops, and the rest of the conjunction continues on the general path
when such a conjunct leaves a variable unbound or bound to a term with
variables in it.

Satisfiers and their order are exactly those of the general engine: atoms of
the state in insertion order, then fact axioms (a predicate whose axioms are
only ground facts, like ``diff-clr``, is matched as a second list), left to
right with backtracking. The generated source depends only on the
conjunction and the mode; the code is cached per conjunction object and mode,
and each planner binds it to its own state's lists when a mode first occurs.
"""

from __future__ import annotations

from collections.abc import Callable

from htn.jshop.language import syntax as S
from htn.jshop.language.terms import Var, is_ground
from htn.jshop.language.walk import walk_expr

from . import warming
from .caches import cache
from .codegen import define, described
from .compile import conjunction
from .conjuncts import ATOM, AXIOM, GENERAL, NOT_ATOM, NOT_AXIOM, Literal, flatten
from .mode_writer import CodeWriter

MAX_LITERALS = 40  # longer conjunctions stay on the general path (indentation)
MAX_VARS = 60  # a mode is a bit mask over the conjunction's variables

_CODE = cache()  # (id(conjunction), mode, sized, entry, indexed) -> factory or None
_LITERALS = cache()  # id(conjunction) -> (conjunctions, _Literals, variables)
_TAILS = cache()  # (id(conjunction), k) -> the conjunction of its conjuncts from k on
_NONE = object()


def compile_conjunction(
    logic, e: S.And, entry: frozenset | None = None, what: str | None = None
) -> Callable:
    """``sat(env)`` for the conjunction ``e`` (see the module docstring).
    ``entry``: the only variables that can be bound when it is asked (a
    precondition's head variables), or None for any. ``what`` names the
    generated code (``precondition of !grasp``; see :mod:`~htn.jshop.logic.codegen`)."""
    hit = _LITERALS.get(e)
    if hit is None:  # the same for every planner of the domain
        items = flatten(e.items)
        lits = [Literal(x, logic.domain.axioms) for x in items]
        hit = _LITERALS.put(e, (items, lits, sorted(set().union(*(lit.vars for lit in lits)))))
    items, lits, names = hit
    if not items:  # only empty conjunctions, nested: true once, as (and)
        return logic.expr(S.And([]))
    general = [logic.expr(x) for x in items]
    gen = conjunction(general) if len(general) > 1 else general[0]
    sized = tuple(lit.sized(logic.arities) for lit in lits)
    if len(lits) > MAX_LITERALS or all(lit.kind == GENERAL for lit in lits):
        return gen
    if entry is not None:
        names = [v for v in names if v in entry]
    if len(names) > MAX_VARS:
        return gen
    state = logic.state
    modes: dict = {}
    indexed = logic.indexes is not None
    hot = logic.hot
    constants = _constants(logic, lits, general, indexed, e, items)
    test = _tester(logic, lits) if len(names) == len(hit[2]) else None
    full = (1 << len(names)) - 1

    def build(mode: int):
        """This mode's code, or None for the general path: a mode is
        compiled when it is met the ``WARM``-th time in the process (see
        :mod:`~htn.jshop.logic.warming`), or at once if an earlier planner of
        the domain compiled it already, or on a ``hot`` engine."""
        key = (id(e), mode, sized, entry, indexed)
        factory = _CODE.get(e, key, _NONE)
        if factory is _NONE:
            met = warming.calls(e, (mode, sized, entry, indexed))
            met[1] += 1
            if met[1] < warming.WARM and not hot:
                return test if mode == full else None
            known = {v for j, v in enumerate(names) if mode >> j & 1}
            factory = _CODE.put(
                e,
                CodeWriter(lits, known, sized, indexed).factory(_mode_name(what, e, known, lits)),
                key,
            )
        f = gen if factory is None else factory(*constants)
        modes[mode] = f
        return f

    return _entry(len(names))(state, gen, modes, build, *names)


def _tester(logic, lits: list):
    """While a conjunction of state atoms and their negations, flat and with
    every variable bound, is warming: its test, interpreted (a set lookup per
    conjunct; an operator's precondition is often just that), or None."""
    plan = []
    for lit in lits:
        if (
            lit.kind not in (ATOM, NOT_ATOM)
            or lit.facts
            or not all(type(a) in (str, float, Var) for a in lit.args)
        ):
            return None
        logic.state.bucket(lit.pred)
        plan.append(
            (
                logic.state.members[lit.pred],
                lit.kind == NOT_ATOM,
                tuple((type(a) is Var, a.index if type(a) is Var else a) for a in lit.args),
            )
        )

    def test(env):
        for members, negated, parts in plan:
            if (tuple([env[x] if var else x for var, x in parts]) in members) is negated:
                return
        yield env

    return test


def _constants(logic, lits: list, general: list, indexed: bool, e: S.And, items: list) -> list:
    """What the generated code of ``lits`` reads from this planner: per
    conjunct, its atoms list and set, its fact axioms ``(heads, counts)``,
    its general satisfier, the conjunction of the conjuncts after it
    (:func:`_rest`), and on a frozen state its atoms' index by bound positions
    (``index(length, positions)``, :meth:`~htn.jshop.logic.engine.Logic.index`)."""
    state = logic.state
    out = []
    for k, lit in enumerate(lits):
        if lit.kind in (ATOM, NOT_ATOM):
            out.append(state.bucket(lit.pred))
            out.append(state.members[lit.pred])
            facts = logic._axioms.get(lit.pred) if lit.facts else None
            out.append(facts[0][1:3] if facts else None)
        elif lit.kind in (AXIOM, NOT_AXIOM):
            out += [logic.solver(lit.pred), None, None]
        else:
            out += [None, None, None]
        out.append(general[k])
        out.append(_rest(logic, e, items, general, k + 1))
        out.append(
            (lambda n, pos, pred=lit.pred: logic.index(pred, n, pos))
            if indexed and lit.kind in (ATOM, NOT_ATOM)
            else None
        )
    return out


def _rest(logic, e: S.And, items: list, general: list, k: int) -> Callable:
    """The conjunction of conjuncts ``k..``, made on first use: the compiled
    code hands it the binding where a conjunct binds a variable to a term
    with variables in it, or where Python's limit on nested loops is near
    (an action of IPC 2020 Woodworking types eleven parameters). It is
    compiled per binding mode in its turn (the tail's conjunction object is
    kept per conjunction, so every planner shares its code)."""
    made: list = []

    def rest(env):
        if not made:
            if len(general) - k > 1:
                tail = _TAILS.make(e, lambda: S.And(items[k:]), (id(e), k))
                made.append(compile_conjunction(logic, tail))
            else:
                made.append(general[k])
        return made[0](env)

    return rest


def _mode_name(what, e: S.And, known: set, lits: list) -> str:
    """``precondition of !grasp, domestic.jshop:41 (bound: ?r ?o)``."""
    names: dict = {}
    for lit in lits:
        walk_expr(lit.expr, lambda v: names.setdefault(v.index, v.name))
    bound = " ".join(names.get(v, f"#{v}") for v in sorted(known)) or "none"
    return f"{described(what or 'conjunction', e.pos)} (bound: {bound})"


_ENTRIES: dict = {}


def _entry(n: int):
    """The function that finds a call's mode and runs that mode's code, for
    a conjunction over ``n`` variables (their indexes are its arguments
    ``v0``..: one piece of code per number of variables, not per conjunction)."""
    make = _ENTRIES.get(n)
    if make is not None:
        return make
    lines = [
        f"def make(state, gen, modes, build{''.join(f', v{j}' for j in range(n))}):",
        "    def sat(env):",
        "        if state.nonground:",
        "            return gen(env)",
        "        m = 0",
    ]
    for j in range(n):
        lines += [
            f"        x = env[v{j}]",
            "        if x is not None:",
            "            if type(x) is str or type(x) is float or is_ground(x):",
            f"                m |= {1 << j}",
            "            else:",
            "                return gen(env)",
        ]
    lines += [
        "        f = modes.get(m)",
        "        if f is None:",
        "            f = build(m)",
        "            if f is None:",
        "                return gen(env)",
        "        return f(env)",
        "    return sat",
    ]
    ns = {"is_ground": is_ground}
    define("\n".join(lines), f"binding mode of a conjunction over {n} variables", ns)
    make = _ENTRIES[n] = ns["make"]
    return make
