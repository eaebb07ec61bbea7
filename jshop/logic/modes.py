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

from itertools import chain
from typing import Callable

from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError
from htn.jshop.language.terms import CallTerm, Var, at_call, is_ground, variables
from htn.jshop.language.walk import walk_expr

from .caches import cache
from .compile import NESTED_CONJUNCTS, conjunction

MAX_LITERALS = 40     # longer conjunctions stay on the general path (indentation)
MAX_VARS = 60         # a mode is a bit mask over the conjunction's variables

_ATOM, _NOT_ATOM, _CALL, _ASSIGN, _GENERAL, _AXIOM, _NOT_AXIOM = range(7)


def _call(func, args, term):
    """A call term's value (arguments ground), placed at the call on error."""
    try:
        return func(args)
    except HtnError as exc:
        raise at_call(exc, term) from None


def _call_nested(func, args, term):
    """Like :func:`_call` for arguments that are themselves calls (whose
    value might not be ground): then the call stays a term, as in ``subst``."""
    if not is_ground(args):
        return CallTerm(term.name, term.func, args, term.pos)
    return _call(func, args, term)


def _vars(t, out: set) -> set:
    """Add the indices of the variables of a term or expression to ``out``."""
    if isinstance(t, (S.Atom, S.VarAtom, S.And, S.Or, S.Not, S.ForAll, S.Equal, S.Assign,
                      S.CallExpr)):
        walk_expr(t, lambda v: out.add(v.index))
    else:
        out.update(v.index for v in variables(t, []))
    return out


def _evaluable(t) -> bool:
    """Whether ``t`` can be computed inline once its variables are bound."""
    tt = type(t)
    if tt is str or tt is float or tt is Var:
        return True
    if tt is tuple:
        return all(_evaluable(x) for x in t)
    if tt is CallTerm:
        return all(_evaluable(x) for x in t.args)
    return False


class _Literal:
    """What one conjunct is, independently of the mode."""
    __slots__ = ("kind", "expr", "pred", "args", "vars", "binds", "facts")

    def __init__(self, expr, axioms: dict):
        self.expr = expr
        self.vars = _vars(expr, set())
        # variables a satisfier may bind (a negation, forall or call binds none)
        self.binds = set() if isinstance(expr, (S.Not, S.ForAll, S.CallExpr)) else self.vars
        self.kind = _GENERAL
        self.facts = False
        atom, kind = expr, _ATOM
        if isinstance(expr, S.Not) and isinstance(expr.expr, S.Atom):
            atom, kind = expr.expr, _NOT_ATOM
        if isinstance(atom, S.Atom):
            axs = axioms.get(atom.pred)
            plain = all(_flat_term(a) for a in atom.args)
            # a flat list argument, like (on ?x ?z) in (goal (on ?x ?z)), is
            # matched element by element in the loop as well
            lists = all(_flat_term(a) or (type(a) is tuple and all(map(_flat_term, a)))
                        for a in atom.args)
            if lists and (not axs or _facts_only(axs)):
                self.kind, self.pred, self.args = kind, atom.pred, atom.args
                self.facts = bool(axs)
            elif plain:       # proved by its axioms, asked directly (Logic.solver)
                self.kind = _AXIOM if kind == _ATOM else _NOT_AXIOM
                self.pred, self.args = atom.pred, atom.args
        elif isinstance(expr, S.CallExpr) and _evaluable(expr.call):
            self.kind = _CALL
        elif isinstance(expr, S.Assign) and _evaluable(expr.term):
            self.kind = _ASSIGN

    def sized(self, arities) -> bool:
        """Can an atom of another length be met (must the length be tested)?"""
        return self.kind in (_ATOM, _NOT_ATOM) and bool(
            self.facts or arities is None or arities.get(self.pred, set()) - {len(self.args)})


def _has_call(t) -> bool:
    tt = type(t)
    return tt is CallTerm or (tt is tuple and any(map(_has_call, t)))


def _flat_term(t) -> bool:
    """A symbol, a number, a variable or nil."""
    return type(t) in (str, float, Var) or t == ()


def _facts_only(axioms: list) -> bool:
    """Whether a predicate's axioms are all facts (``(:- (diff-clr s h) nil)``),
    which :class:`htn.jshop.logic.engine.Logic` matches as one list of heads."""
    return all(is_ground(ax.head.args) and always(ax.branches[0].pre) for ax in axioms)


def _flatten(items: list) -> list:
    out = []
    for x in items:
        if isinstance(x, S.And):
            out.extend(_flatten(x.items))
        else:
            out.append(x)
    return out


_CODE: dict = cache()    # (id(conjunction), mode, sized, entry) -> (conjunction, factory or None)
_LITERALS: dict = cache()  # id(conjunction) -> (conjunction, conjuncts, _Literals, variables)


def always(pre: S.Precondition) -> bool:
    """An empty precondition (``nil``): exactly one satisfier, the binding itself."""
    e = pre.expr
    return isinstance(e, S.And) and not e.items and pre.sort_var is None


def compile_conjunction(logic, e: S.And, entry: frozenset = None) -> Callable:
    """``sat(env)`` for the conjunction ``e`` (see the module docstring).
    ``entry``: the only variables that can be bound when it is asked (a
    precondition's head variables), or None for any."""
    hit = _LITERALS.get(id(e))
    if hit is None or hit[0] is not e:     # the same for every planner of the domain
        items = _flatten(e.items)
        lits = [_Literal(x, logic.domain.axioms) for x in items]
        hit = _LITERALS[id(e)] = (e, items, lits, sorted(set().union(*(l.vars for l in lits))))
    _, items, lits, names = hit
    general = [logic.expr(x) for x in items]
    gen = conjunction(general) if len(general) > 1 else general[0]
    sized = tuple(lit.sized(logic.arities) for lit in lits)
    if len(lits) > MAX_LITERALS or all(lit.kind == _GENERAL for lit in lits):
        return gen
    if entry is not None:
        names = [v for v in names if v in entry]
    if len(names) > MAX_VARS:
        return gen
    state = logic.state
    modes: dict = {}
    met: set = set()      # the modes met once, whose code was not written yet
    constants = _constants(logic, lits, general)

    def build(mode: int):
        """This mode's code, or None for the general path: a mode met for
        the first time is not worth compiling (a tiny search meets it once),
        unless an earlier planner of the domain compiled it already."""
        key = (id(e), mode, sized, entry)
        hit = _CODE.get(key)
        if hit is None or hit[0] is not e:
            if mode not in met:
                met.add(mode)
                return None
            known = {v for j, v in enumerate(names) if mode >> j & 1}
            hit = _CODE[key] = (e, _Writer(lits, known, sized).factory())
        factory = hit[1]
        f = gen if factory is None else factory(*constants)
        modes[mode] = f
        return f

    return _entry(names)(state, gen, modes, build)


def _constants(logic, lits: list, general: list) -> list:
    """What the generated code of ``lits`` reads from this planner: per
    conjunct, its atoms list and set, its fact axioms ``(heads, counts)``,
    its general satisfier, and the general conjunction of the conjuncts
    after it."""
    state = logic.state
    out = []
    for k, lit in enumerate(lits):
        if lit.kind in (_ATOM, _NOT_ATOM):
            out.append(state.bucket(lit.pred))
            out.append(state.members[lit.pred])
            facts = logic._axioms.get(lit.pred) if lit.facts else None
            out.append(facts[0][1:3] if facts else None)
        elif lit.kind in (_AXIOM, _NOT_AXIOM):
            out += [logic.solver(lit.pred), None, None]
        else:
            out += [None, None, None]
        out.append(general[k])
        out.append(_rest(general, k + 1))
    return out


def _rest(general: list, k: int) -> Callable:
    """The general conjunction of ``general[k:]``, made on first use (the
    compiled code needs it only when a conjunct binds a variable to a term
    with variables in it)."""
    made: list = []

    def rest(env):
        if not made:
            tail = general[k:]
            made.append(conjunction(tail) if len(tail) > 1 else tail[0])
        return made[0](env)
    return rest


_ENTRIES: dict = {}


def _entry(names: list):
    """The function that finds a call's mode and runs that mode's code."""
    key = tuple(names)
    make = _ENTRIES.get(key)
    if make is not None:
        return make
    lines = ["def make(state, gen, modes, build):",
             "    def sat(env):",
             "        if state.nonground:",
             "            return gen(env)",
             "        m = 0"]
    for j, v in enumerate(names):
        lines += [f"        x = env[{v}]",
                  "        if x is not None:",
                  "            if type(x) is str or type(x) is float or is_ground(x):",
                  f"                m |= {1 << j}",
                  "            else:",
                  "                return gen(env)"]
    lines += ["        f = modes.get(m)",
              "        if f is None:",
              "            f = build(m)",
              "            if f is None:",
              "                return gen(env)",
              "        return f(env)",
              "    return sat"]
    ns = {"is_ground": is_ground}
    exec("\n".join(lines), ns)
    make = _ENTRIES[key] = ns["make"]
    return make


class _Writer:
    """Writes the generator of one conjunction under one mode."""

    def __init__(self, lits: list, known: set, sized: tuple):
        self.lits = lits
        self.sized = sized
        self.entry = set(known)
        self.known = set(known)
        self.ns: dict = {"_call": _call, "_call_nested": _call_nested, "chain": chain,
                         "is_ground": is_ground, "HtnError": HtnError}
        self.lines: list = []
        self.depth = 2           # indentation, in levels of four spaces
        self.loops = 0
        self.base = "env"        # the binding list holding every variable not in a local
        self.local: set = set()  # variables held in locals and not yet in ``base``
        self.n = 0

    def emit(self, line: str) -> None:
        self.lines.append("    " * self.depth + line)

    def const(self, value) -> str:
        name = f"k{self.n}"
        self.n += 1
        self.ns[name] = value
        return name

    def term(self, t, direct: bool = False) -> str:
        """The expression computing ``t`` (its variables known). ``direct``:
        calls are made without :func:`_call`, for :meth:`value`."""
        tt = type(t)
        if tt is Var:
            return f"x{t.index}"
        if tt is tuple:
            return "(" + "".join(self.term(x, direct) + ", " for x in t) + ")"
        if tt is CallTerm:
            args = "(" + "".join(self.term(x, direct) + ", " for x in t.args) + ")"
            if direct:
                return f"{self.const(t.func)}({args})"
            nested = any(type(x) is CallTerm or type(x) is tuple for x in t.args)
            helper = "_call_nested" if nested else "_call"
            return f"{helper}({self.const(t.func)}, {args}, {self.const(t)})"
        return self.const(t)

    def value(self, target: str, t) -> None:
        """Emit ``target = t``. Its calls are made directly, in one ``try``:
        every value met here is ground (a known variable is bound to a ground
        term, a function's value is ground), so :func:`_call_nested` would
        never keep a call as a term. Only when a call fails is the term
        computed again through :func:`_call`, which places the error at the
        failing call (as ``compile._fast_path`` does)."""
        if not _has_call(t):
            self.emit(f"{target} = {self.term(t)}")
            return
        fast = self.term(t, direct=True)
        slow = self.term(t)
        self.emit("try:")
        self.emit(f"    {target} = {fast}")
        self.emit("except HtnError:")
        self.emit(f"    {target} = {slow}")

    def factory(self):
        """The code's factory ``make(*constants) -> run``, or None when this
        mode gains nothing (every conjunct would take the general path)."""
        lits = self.lits
        if all(lit.kind == _GENERAL or (lit.kind == _ASSIGN and not _vars(lit.expr.term, set()) <= self.known)
               for lit in lits):
            return None
        for v in sorted(self.entry & set().union(*(lit.vars for lit in lits))):
            self.emit(f"x{v} = env[{v}]")
        for k in range(len(lits)):
            if not self.literal(k):
                break
        else:
            self.finish()
        if self.loops > NESTED_CONJUNCTS:
            return None
        params = []
        for k in range(len(lits)):
            params += [f"L{k}", f"M{k}", f"H{k}", f"G{k}", f"R{k}"]
        src = [f"def make({', '.join(params)}):", "    def run(env):", *self.lines,
               "    return run"]
        exec("\n".join(src), self.ns)
        return self.ns["make"]

    def finish(self) -> None:
        if self.local:
            self.emit(f"new = {self.base}[:]")
            for v in sorted(self.local):
                self.emit(f"new[{v}] = x{v}")
            self.emit("yield new")
        else:
            self.emit(f"yield {self.base}")

    def literal(self, k: int) -> bool:
        """Write conjunct ``k``; False if it ended the code (the rest of the
        conjunction was handed to the general path)."""
        lit = self.lits[k]
        kind = lit.kind
        if kind == _ASSIGN and lit.expr.var.index not in self.known \
                and not _vars(lit.expr.term, set()) <= self.known:
            kind = _GENERAL
        if kind == _ATOM or kind == _NOT_ATOM:
            self.atom(k, lit, kind == _NOT_ATOM)
        elif kind == _NOT_AXIOM:
            ground = all(type(a) is not Var or a.index in self.known for a in lit.args)
            self.emit(f"if next(L{k}({self.bound(lit.args)}, env, {ground}), None) is None:")
            self.depth += 1
        elif kind == _AXIOM:
            ground = all(type(a) is not Var or a.index in self.known for a in lit.args)
            return self.general(k, lit, f"L{k}({self.bound(lit.args)}, {{}}, {ground})")
        elif kind == _CALL and not lit.vars <= self.known:
            # a call with a free variable stays a term, which is not nil: the
            # conjunct holds, once the calls inside it that can be evaluated
            # have been (they may fail), as ``subst`` evaluates them
            self.inner_calls(lit.expr.call)
        elif kind == _CALL:
            self.value(f"v{k}", lit.expr.call)
            self.emit(f"if not (type(v{k}) is tuple and not v{k}):")
            self.depth += 1
        elif kind == _ASSIGN:
            v = lit.expr.var.index
            if v not in self.known:     # an earlier binding wins, as in JSHOP2
                self.value(f"x{v}", lit.expr.term)
                self.known.add(v)
                self.local.add(v)
        else:
            return self.general(k, lit)
        return True

    def inner_calls(self, t) -> None:
        """Evaluate, for their errors only, the calls in ``t`` whose variables
        are all bound, in ``subst``'s order (arguments left to right)."""
        tt = type(t)
        if tt is CallTerm and _vars(t, set()) <= self.known:
            self.emit(self.term(t))
        elif tt is CallTerm or tt is tuple:
            for x in (t.args if tt is CallTerm else t):
                self.inner_calls(x)

    def atom(self, k: int, lit: _Literal, negated: bool) -> None:
        args = lit.args
        if lit.vars <= self.known:
            tup = self.term(args)
            if negated:
                test = f"{tup} not in M{k}"
                if lit.facts:
                    test += f" and {tup} not in H{k}[1]"
                self.emit(f"if {test}:")
            elif lit.facts:    # a ground fact may be stated more than once
                self.emit(f"t{k} = {tup}")
                self.emit(f"for _ in range((t{k} in M{k}) + H{k}[1].get(t{k}, 0)):")
                self.loops += 1
            else:
                self.emit(f"if {tup} in M{k}:")
            self.depth += 1
            return
        conds = [f"len(t) == {len(args)}"] if self.sized[k] else []
        binds = []
        first: dict = {}      # variable -> where it is first met in ``t``
        for i, a in enumerate(args):
            if type(a) is tuple and a and not _vars(a, set()) <= self.known:
                # a list with a free variable: its shape, then element by element
                conds.append(f"type(t[{i}]) is tuple and len(t[{i}]) == {len(a)}")
                for j, x in enumerate(a):
                    self.match(f"t[{i}][{j}]", x, conds, binds, first)
            else:
                self.match(f"t[{i}]", a, conds, binds, first)
        source = f"chain(L{k}, H{k}[0])" if lit.facts else f"L{k}"
        cond = " and ".join(conds) or "True"
        if negated:
            self.emit(f"ok{k} = True")
            self.emit(f"for t in {source}:")
            self.emit(f"    if {cond}:")
            self.emit(f"        ok{k} = False")
            self.emit("        break")
            self.emit(f"if ok{k}:")
            self.depth += 1
            self.loops += 1
            return
        # an inner loop reuses ``t``: this loop reads it only before going in
        self.emit(f"for t in {source}:")
        self.depth += 1
        self.loops += 1
        self.emit(f"if {cond}:")
        self.depth += 1
        for b in binds:
            self.emit(b)
        self.known |= set(first)
        self.local |= set(first)

    def match(self, place: str, a, conds: list, binds: list, first: dict) -> None:
        """Match the pattern term ``a`` (flat) with ``place`` of an atom, as
        unifying does with a ground atom: a free variable binds at its first
        place and must be equal at the others; anything else must be equal."""
        if type(a) is Var and a.index not in self.known:
            if a.index in first:
                conds.append(f"{place} == {first[a.index]}")
            else:
                first[a.index] = place
                binds.append(f"x{a.index} = {place}")
        else:
            conds.append(f"{place} == {self.term(a)}")

    def bound(self, args: tuple) -> str:
        """The atom's arguments as the general engine's binder gives them:
        bound variables by their values, unbound ones as themselves."""
        return "(" + "".join((f"x{a.index}" if type(a) is Var and a.index in self.known
                              else self.const(a)) + ", " for a in args) + ")"

    def general(self, k: int, lit: _Literal, call: str = "G{k}({})") -> bool:
        """Conjunct ``k`` asked of the general engine (``call`` names the
        satisfier, ``{}`` standing for the binding list)."""
        call = call.replace("{k}", str(k))
        if self.local:
            self.emit(f"e{k} = {self.base}[:]")
            for v in sorted(self.local):
                self.emit(f"e{k}[{v}] = x{v}")
            arg = f"e{k}"
        else:
            arg = self.base
        last = k == len(self.lits) - 1
        if last:
            self.emit(f"yield from {call.format(arg)}")
            return False
        self.emit(f"for b{k} in {call.format(arg)}:")
        self.depth += 1
        self.loops += 1
        self.base, self.local = f"b{k}", set()
        new = sorted(lit.binds - self.known)
        if new:
            for v in new:
                self.emit(f"x{v} = b{k}[{v}]")
            ground = " and ".join(f"(type(x{v}) is str or type(x{v}) is float or "
                                  f"(x{v} is not None and is_ground(x{v})))" for v in new)
            self.emit(f"if not ({ground}):")
            self.emit(f"    yield from R{k}(b{k})")
            self.emit("    continue")
            self.known |= set(new)
        return True
