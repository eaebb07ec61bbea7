"""The logic engine: satisfiers of logical expressions in a state (manual 5.1.2).

Each expression is compiled once into a function ``sat(env)`` that lazily yields
extended bindings (Python lists indexed by variable number), in the order the
Java JSHOP2 finds them: state atoms in insertion order, then axioms in
definition order; conjunctions left to right with backtracking; disjunctions
disjunct by disjunct. Laziness matters: the planner keeps a precondition's
generator open while it searches below one binding, exactly as JSHOP2 keeps its
precondition iterator, and the state is restored before the next binding.

Axioms follow 3.6: a later branch is tried only if no earlier branch had a
satisfier. ``:first`` keeps the first satisfier, ``:sort-by`` sorts all of them
with Java's sort algorithm (see :mod:`~htn.jshop.logic.java_sort`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator

from htn.jshop.language import syntax as S
from htn.jshop.language.errors import PlanningError
from htn.jshop.language.terms import (
    Var,
    atom_from_term,
    is_ground,
    source_atom,
    source_str,
    subst,
    unify,
    variables,
)

from . import warming as warm
from .caches import cache
from .codegen import described
from .compile import GENERIC
from .conjuncts import always, arities
from .java_sort import sorted_by
from .modes import compile_conjunction
from .scan import scan_atoms

_HEADS = cache()


def head_variables(args: tuple) -> frozenset:
    """The indices of the variables of a head (cached by the head's tuple)."""
    return _HEADS.make(args, lambda: frozenset(v.index for v in variables(args, [])))


Sat = Callable[[list], Iterator[list]]


def _unify_args(pattern: tuple, args: tuple, env: list) -> bool:
    if len(pattern) != len(args):
        return False
    for p, t in zip(pattern, args):
        if not unify(p, t, env):
            return False
    return True


class Logic:
    """Compiles expressions of one domain against one (mutable) state."""

    def __init__(self, domain: S.Domain, state, functions=None):
        self.domain = domain
        self.state = state
        self.functions = functions
        self.arities = arities(domain, state)
        # (pred, length, positions) -> {values there: atoms}, once the state
        # is frozen (see freeze); None while it may change
        self.indexes: dict | None = None
        # compile a conjunction's binding mode at its first call, without
        # warming (grounding: every call is a join over the whole state)
        self.hot = False
        # axiom bodies refer to axioms (their own predicate too): every list
        # exists before any body is compiled, and is filled in place
        self._axioms: dict[str, list] = {pred: [] for pred in domain.axioms}
        for pred, axs in domain.axioms.items():
            self._axioms[pred][:] = self._segments(axs)

    def freeze(self) -> None:
        """Promise that the state will not change any more: conjunctions
        compiled from now on find the atoms that agree with their bound
        arguments through an index (:meth:`index`) instead of scanning the
        predicate's atoms. Grounding's reachable facts are such a state."""
        if self.indexes is None:
            self.indexes = {}

    def index(self, pred: str, length: int, positions: tuple) -> dict:
        """The frozen state's atoms of ``pred`` with ``length`` arguments by
        their values at ``positions``, each list in the state's order (so a
        lookup gives the atoms a scan would match, in the scan's order)."""
        assert self.indexes is not None, "index of a state that may change"
        key = (pred, length, positions)
        found = self.indexes.get(key)
        if found is None:
            found = self.indexes[key] = {}
            for t in self.state.bucket(pred):
                if len(t) == length:
                    v = tuple([t[p] for p in positions])
                    lst = found.get(v)
                    if lst is None:
                        found[v] = [t]
                    else:
                        lst.append(t)
        return found

    def _segments(self, axs: list) -> list:
        """A predicate's axioms, in definition order, as segments: a run of
        facts (a ground head whose first branch is empty, ``(:- (diff-clr s
        h) nil)``) is matched like state atoms, in one scan; any other axiom
        is proved by its branches (3.6). The satisfiers and their order are
        those of proving each axiom in turn."""
        segments: list = []
        for ax in axs:
            if is_ground(ax.head.args) and always(ax.branches[0].pre):
                if not segments or segments[-1][0] is not _FACTS:
                    segments.append((_FACTS, [], {}, None, None))
                _, heads, counts, _, _ = segments[-1]
                heads.append(ax.head.args)
                counts[ax.head.args] = counts.get(ax.head.args, 0) + 1
            else:
                segments.append(self._axiom(ax))
        return segments

    def _axiom(self, ax: S.Axiom) -> list:
        """``[axiom, head unifier, head binder, branches, flat head]`` (the
        unifier and binder warming: compiled ones replace them in place)."""
        args = ax.head.args
        head = source_atom(ax.head.pred, args)
        seg: list = [
            ax,
            None,
            None,
            [
                self.precondition(b.pre, args, f"precondition of axiom {head} branch {b.label}")
                for b in ax.branches
            ],
            all(type(a) in (str, float, Var) for a in args),
        ]
        seg[1] = warm.head_unifier(
            args,
            lambda: described(f"unifier of the axiom head {head}", ax.pos),
            lambda f: seg.__setitem__(1, f),
        )
        seg[2] = warm.binder(
            args,
            lambda: described(f"binding of the axiom head {head}", ax.pos),
            lambda f: seg.__setitem__(2, f),
        )
        return seg

    # ------------------------------------------------------------ preconditions
    def precondition(
        self, pre: S.Precondition, head: tuple | None = None, what: str | None = None
    ) -> Sat:
        """``head``: the arguments of the method's, operator's or axiom's head,
        whose variables are the only ones bound when the precondition is
        asked (the binding is fresh), so only they decide its binding mode.
        ``what`` names the generated code (``precondition of !grasp``)."""
        e = pre.expr
        if isinstance(e, (S.Atom, S.Not)):  # one literal: compiled as a conjunction of one
            e = _single(e)
        if isinstance(e, S.And) and e.items and (head is not None or what is not None):
            sat = compile_conjunction(self, e, None if head is None else head_variables(head), what)
        else:
            sat = self.expr(e)
        if pre.first:

            def first(env, sat=sat):
                for e in sat(env):
                    yield e
                    return

            return first
        if pre.sort_var is not None:
            return sorted_by(sat, pre, self.functions)
        return sat

    # ------------------------------------------------------------ expressions
    def expr(self, e) -> Sat:
        method = getattr(self, "_" + type(e).__name__.lower())
        return method(e)

    def _and(self, e: S.And) -> Sat:
        if not e.items:
            return _true
        return compile_conjunction(self, e)

    def _or(self, e: S.Or) -> Sat:
        sats = [self.expr(x) for x in e.items]

        def disj(env):
            for s in sats:
                yield from s(env)

        return disj

    def _not(self, e: S.Not) -> Sat:
        if isinstance(e.expr, S.Atom):
            return self._not_atom(e.expr)
        sat = self.expr(e.expr)

        def neg(env):
            for _ in sat(env):
                return
            yield env

        return neg

    def _forall(self, e: S.ForAll) -> Sat:
        cond, then = self.expr(e.cond), self.expr(e.then)

        def forall(env):
            for c in cond(env):
                for _ in then(c):
                    break
                else:
                    return
            yield env

        return forall

    def _equal(self, e: S.Equal) -> Sat:
        left, right, pos = e.left, e.right, e.pos

        def equal(env):
            a, b = subst(left, env), subst(right, env)
            if type(a) is Var:
                if type(b) is Var:
                    raise PlanningError.at(
                        pos, f"(= {a.name} {b.name}) compares two unbound variables"
                    )
                new = env[:]
                new[a.index] = b
                yield new
            elif type(b) is Var:
                new = env[:]
                new[b.index] = a
                yield new
            elif a == b and type(a) is type(b):
                yield env

        return equal

    def _term_binder(self, term, pos, install):
        return warm.term_binder(
            term, lambda: described(f"value of {source_str(term)}", pos), install
        )

    def _assign(self, e: S.Assign) -> Sat:
        idx = e.var.index

        def install(f):
            nonlocal bind
            bind = f

        bind = self._term_binder(e.term, e.pos, install)

        def assign(env):
            if env[idx] is not None:  # JSHOP2 merges: an earlier binding wins
                yield env
                return
            new = env[:]
            new[idx] = bind(env)[1][0]
            yield new

        return assign

    def _callexpr(self, e: S.CallExpr) -> Sat:
        def install(f):
            nonlocal bind
            bind = f

        bind = self._term_binder(e.call, e.pos, install)

        def callexpr(env):
            v = bind(env)[1][0]
            if type(v) is tuple and not v:
                return
            yield env

        return callexpr

    def _varatom(self, e: S.VarAtom) -> Sat:
        idx, pos = e.var.index, e.pos

        def varatom(env):
            t = env[idx]
            if t is None:
                raise PlanningError.at(
                    pos, f"variable {e.var.name} is used as an atom but is not bound"
                )
            pred, args = atom_from_term(t, pos)
            yield from self.match(pred, args, env)

        return varatom

    def _lookup(self, e: S.Atom, install) -> tuple:
        """What an atom test holds on to: the binder of its arguments (warming,
        ``install`` puts the compiled one in place), its predicate's atom list
        and set (the state keeps them for good), its axioms, and a function
        giving the scanner of a binding key (warming too)."""
        pred, args = e.pred, e.args
        shown = lambda: source_atom(pred, args)  # noqa: E731 - names compiled code
        scanners: dict = {}

        def scanner(key):
            scan = scanners[key] = warm.scanner(
                args,
                key,
                lambda: described(f"atoms matching {shown()}", e.pos),
                lambda f: scanners.__setitem__(key, f),
            )
            return scan

        bind = warm.binder(args, lambda: described(f"binding of {shown()}", e.pos), install)
        return (
            bind,
            self.state.bucket(pred),
            self.state.members[pred],
            self._axioms.get(pred),
            scanners,
            scanner,
        )

    def _atom(self, e: S.Atom) -> Sat:
        prove = self._prove

        def install(f):
            nonlocal bind
            bind = f

        bind, lst, members, axioms, scanners, scanner = self._lookup(e, install)

        def atom(env):
            key, bound = bind(env)
            if key is None:
                if bound in members:
                    yield env
            elif key >= GENERIC:
                yield from scan_atoms(lst, bound, env)
            else:
                yield from (scanners.get(key) or scanner(key))(lst, bound, env)
            if axioms:
                yield from prove(axioms, bound, env, key is None)

        return atom

    def _not_atom(self, e: S.Atom) -> Sat:
        """``(not (p ...))``: the same test as :meth:`_atom`, stopping at the
        first satisfier without making generators for it (the most common
        negation, so worth its own code)."""
        prove = self._prove

        def install(f):
            nonlocal bind
            bind = f

        bind, lst, members, axioms, scanners, scanner = self._lookup(e, install)

        def neg(env):
            key, bound = bind(env)
            if key is None:
                if bound in members:
                    return
            elif key >= GENERIC:
                if next(scan_atoms(lst, bound, env), None) is not None:
                    return
            elif next((scanners.get(key) or scanner(key))(lst, bound, env), None) is not None:
                return
            if axioms and next(prove(axioms, bound, env, key is None), None) is not None:
                return
            yield env

        return neg

    # ------------------------------------------------------------ atoms
    def solver(self, pred: str) -> Callable:
        """``solve(bound, env, ground)``: the satisfiers of ``(pred . bound)``
        as :meth:`_atom` finds them (state atoms, then axioms), for a caller
        that knows already whether ``bound`` is ground (htn.jshop.logic.modes)."""
        lst = self.state.bucket(pred)
        members = self.state.members[pred]
        axioms = self._axioms.get(pred)
        prove = self._prove

        def solve(bound, env, ground):
            if ground:
                if bound in members:
                    yield env
            elif lst:
                yield from scan_atoms(lst, bound, env)
            if axioms:
                yield from prove(axioms, bound, env, ground)

        return solve

    def match(self, pred: str, bound: tuple, env: list) -> Iterator[list]:
        """Satisfiers of the atom ``(pred . bound)``: state atoms, then axioms."""
        state = self.state
        if is_ground(bound):
            if state.has(pred, bound):
                yield env
        else:
            yield from scan_atoms(state.bucket(pred), bound, env)
        axioms = self._axioms.get(pred)
        if axioms:
            yield from self._prove(axioms, bound, env)

    def _prove(self, axioms, bound: tuple, env: list, ground=None) -> Iterator[list]:
        """Satisfiers of ``(pred . bound)`` by the predicate's axioms (3.6).

        When ``bound`` is ground and an axiom's head is flat, the head under
        any satisfier of a branch is ``bound`` itself (every head variable
        was bound by unifying the head), so ``env`` is yielded unchanged."""
        if ground is None:
            ground = is_ground(bound)
        for ax, unify_head, bind_head, branches, flat in axioms:
            if ax is _FACTS:  # (unify_head, bind_head) are (heads, counts) here
                if ground:
                    for _ in range(bind_head.get(bound, 0)):
                        yield env
                else:
                    yield from scan_atoms(unify_head, bound, env)
                continue
            aenv = [None] * ax.nvars
            if not unify_head(bound, aenv):
                continue
            for sat in branches:
                found = False
                try:
                    if ground and flat:
                        for _ in sat(aenv):
                            found = True
                            yield env
                        if found:
                            break
                        continue
                    for nb in sat(aenv):
                        head = bind_head(nb)[1]
                        new = env[:]
                        if _unify_args(bound, head, new):
                            found = True
                            yield new
                except RecursionError:  # JSHOP2 overflows its stack here too
                    raise PlanningError.at(
                        ax.pos,
                        f"proving an axiom for {ax.head.pred} "
                        "recursed too deeply: does it depend on itself?",
                    ) from None
                if found:
                    break


_SINGLES = cache()


def _single(e) -> S.And:
    """The conjunction of ``e`` alone, one object per ``e`` (the compiled
    code is cached by conjunction object)."""
    return _SINGLES.make(e, lambda: S.And([e], getattr(e, "pos", None)))


def _true(env):
    yield env


_FACTS = object()  # marks a run of fact axioms, see Logic._segments
