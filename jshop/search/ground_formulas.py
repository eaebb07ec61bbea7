"""Ground formulas over a numbered set of facts, for the grounded search.

A precondition instantiated with a binding of its element's variables is
evaluated as far as the facts that never change allow (the *static*
predicates: types and every predicate no action adds or deletes, read from
the initial state), which leaves a *residual* over the dynamic facts:
``True``, ``False``, ``("lit", bit, positive)``, ``("and", items)`` or
``("or", items)``. A dynamic atom that the delete-relaxed reachability
analysis never reaches is false in every reachable state.

``forall`` (JSHOP2's ``(forall V Y Z)``: every satisfier of Y satisfies Z)
is expanded over the satisfiers of Y's relaxation in the reachable facts,
each contributing ``not Y or Z``. A residual compiles to
``(positive mask, negative mask, rest)``: the conjunction of literals at its
top as bit masks of a state (an ``int``), the rest as trees for
:func:`holds`.
"""

from __future__ import annotations

from htn.jshop.language import syntax as S
from htn.jshop.language.terms import subst, variables
from htn.jshop.logic.caches import IdentityCache

from .residual_code import compile_formula

COMPILE_AFTER = 32  # groundings of a formula before it is compiled


class NotGroundable(Exception):
    """A construct the grounded search does not handle (calls, assignments,
    cost terms): the caller falls back to depth-first search."""


def relax(e):
    """The delete relaxation of a formula: negations and ``forall`` are
    dropped (taken as true), so every state that satisfies ``e`` satisfies it."""
    if isinstance(e, (S.Atom, S.Equal)):
        return e
    if isinstance(e, S.And):
        return S.And([relax(x) for x in e.items], e.pos)
    if isinstance(e, S.Or):
        return S.Or([relax(x) for x in e.items], e.pos)
    if isinstance(e, (S.Not, S.ForAll)):
        return S.And([])
    raise NotGroundable(f"{type(e).__name__} in a precondition")


def mentions(x, slots: set[int]) -> bool:
    """Whether a formula mentions any of the variable slots, anywhere
    (anything it does not know is taken to)."""
    stack = [x]
    while stack:
        y = stack.pop()
        if isinstance(y, (S.And, S.Or)):
            stack.extend(y.items)
        elif isinstance(y, S.Not):
            stack.append(y.expr)
        elif isinstance(y, S.ForAll):
            stack += [y.cond, y.then]
            if {v.index for v in y.vars} & slots:
                return True
        elif isinstance(y, S.Atom):
            if _indices(y.args) & slots:
                return True
        elif isinstance(y, S.Equal):
            if _indices((y.left, y.right)) & slots:
                return True
        else:
            return True
    return False


def _indices(args: tuple) -> set[int]:
    return {v.index for v in variables(args, [])}


def flat_and(items: list) -> S.And:
    """A conjunction of ``items`` with nested conjunctions flattened."""
    out, stack = [], list(reversed(items))
    while stack:
        x = stack.pop()
        if isinstance(x, S.And):
            stack.extend(reversed(x.items))
        else:
            out.append(x)
    return S.And(out)


def conj(items: list):
    out = []
    for x in items:
        if x is False:
            return False
        if x is True:
            continue
        if type(x) is tuple and x[0] == "and":
            out.extend(x[1])
        else:
            out.append(x)
    if not out:
        return True
    return out[0] if len(out) == 1 else ("and", tuple(out))


def disj(items: list):
    out = []
    for x in items:
        if x is True:
            return True
        if x is False:
            continue
        if type(x) is tuple and x[0] == "or":
            out.extend(x[1])
        elif x not in out:
            out.append(x)
    if not out:
        return False
    return out[0] if len(out) == 1 else ("or", tuple(out))


def negate(x):
    if x is True or x is False:
        return not x
    kind = x[0]
    if kind == "lit":
        return ("lit", x[1], not x[2])
    if kind == "and":
        return disj([negate(y) for y in x[1]])
    return conj([negate(y) for y in x[1]])


class FormulaGrounder:
    """Residuals of formulas under bindings (see the module docstring).

    ``static``: ``pred -> set of args`` of the static predicates' atoms;
    ``bits``: ``(pred, args) -> bit`` of the reachable dynamic atoms;
    ``relaxed``: a :class:`~htn.jshop.logic.engine.Logic` over the reachable
    facts, whose satisfiers expand quantifiers."""

    def __init__(self, static: dict, bits: dict, relaxed):
        self.static = static
        self.bits = bits
        self.relaxed = relaxed
        self._sat = IdentityCache(global_=False)  # formula -> its satisfier
        self._code = IdentityCache(global_=False)  # formula -> [uses, compiled or None]

    def ground(self, e, env: list):
        """The residual of ``e`` under ``env``: walked while a formula is new,
        compiled (:mod:`~htn.jshop.search.residual_code`) once it has been
        grounded ``COMPILE_AFTER`` times."""
        hit = self._code.get(e)
        if hit is None:
            hit = self._code.put(e, [0, None])
        code = hit[1]
        if code is not None:
            return code(env)
        hit[0] += 1
        if hit[0] >= COMPILE_AFTER:
            hit[1] = compile_formula(self, e, _HELPERS)
        return self.walk(e, env)

    def satisfiers(self, e, env: list):
        """Bindings extending ``env`` that satisfy ``e``'s relaxation in the
        reachable facts (copies: the caller may keep them)."""
        sat = self._sat.make(e, lambda: self.relaxed.expr(flat_and([relax(e)])))
        for nb in sat(list(env)):
            yield list(nb)

    def walk(self, e, env: list):
        """:meth:`ground` by walking the formula."""
        if isinstance(e, S.Atom):
            args = subst(e.args, env)
            facts = self.static.get(e.pred)
            if facts is not None:
                return args in facts
            bit = self.bits.get((e.pred, args))
            return False if bit is None else ("lit", bit, True)
        if isinstance(e, S.And):
            out = []
            for x in e.items:
                g = self.walk(x, env)
                if g is False:
                    return False
                out.append(g)
            return conj(out)
        if isinstance(e, S.Or):
            return disj([self.walk(x, env) for x in e.items])
        if isinstance(e, S.Not):
            return negate(self.walk(e.expr, env))
        if isinstance(e, S.Equal):
            return subst(e.left, env) == subst(e.right, env)
        if isinstance(e, S.ForAll):
            out = []
            for nb in self.satisfiers(e.cond, env):
                out.append(disj([negate(self.ground(e.cond, nb)), self.ground(e.then, nb)]))
                if out[-1] is False:
                    return False
            return conj(out)
        raise NotGroundable(f"{type(e).__name__} in a precondition")


_HELPERS = {"conj": conj, "disj": disj, "negate": negate}


def compile_residual(r) -> tuple | None:
    """``(positive mask, negative mask, rest)``, or None when ``r`` is False."""
    if r is False:
        return None
    items = [] if r is True else (list(r[1]) if r[0] == "and" else [r])
    pos = neg = 0
    rest = []
    for x in items:
        if x[0] == "lit":
            if x[2]:
                pos |= 1 << x[1]
            else:
                neg |= 1 << x[1]
        else:
            rest.append(x)
    if pos & neg:
        return None
    return pos, neg, tuple(rest)


def holds(tree, s: int) -> bool:
    """A residual tree in state ``s``."""
    kind = tree[0]
    if kind == "lit":
        return bool(s >> tree[1] & 1) is tree[2]
    if kind == "and":
        return all(holds(x, s) for x in tree[1])
    return any(holds(x, s) for x in tree[1])


def satisfied(pre: tuple, s: int) -> bool:
    """A compiled residual ``(pos, neg, rest)`` in state ``s``."""
    pos, neg, rest = pre
    if s & pos != pos or s & neg:
        return False
    for tree in rest:
        if not holds(tree, s):
            return False
    return True


def positive_bits(tree) -> list:
    """The facts a residual tree needs in every case (its positive literals
    under conjunctions), for the relaxed heuristic."""
    if tree[0] == "lit":
        return [tree[1]] if tree[2] else []
    if tree[0] == "and":
        return [b for x in tree[1] for b in positive_bits(x)]
    return []


def bits(mask: int) -> list:
    """The indices of the bits set in ``mask``, lowest first."""
    out = []
    while mask:
        low = mask & -mask
        out.append(low.bit_length() - 1)
        mask ^= low
    return out
