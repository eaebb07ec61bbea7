"""The code of one conjunction under one binding mode: nested loops over
Python locals (see :mod:`htn.jshop.logic.modes`, which compiles and caches it)."""

from __future__ import annotations

from itertools import chain

from htn.jshop.language.errors import HtnError
from htn.jshop.language.terms import CallTerm, Var, is_ground

from .codegen import define
from .compile import NESTED_CONJUNCTS
from .conjuncts import (
    ASSIGN,
    ATOM,
    AXIOM,
    CALL,
    GENERAL,
    NOT_ATOM,
    NOT_AXIOM,
    Literal,
    call_at,
    call_nested,
    has_call,
    term_vars,
)


class CodeWriter:
    """Writes the generator of one conjunction under one mode."""

    def __init__(self, lits: list, known: set, sized: tuple, indexed: bool = False):
        self.lits = lits
        self.sized = sized
        self.indexed = indexed  # a frozen state: look atoms up by their bound arguments
        self.pre: list = []  # lines of ``make``, run once when the code is bound
        self.entry = set(known)
        self.known = set(known)
        self.ns: dict = {
            "call_at": call_at,
            "call_nested": call_nested,
            "chain": chain,
            "is_ground": is_ground,
            "HtnError": HtnError,
        }
        self.lines: list = []
        self.depth = 2  # indentation, in levels of four spaces
        self.loops = 0
        self.base = "env"  # the binding list holding every variable not in a local
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
        calls are made without :func:`call_at`, for :meth:`value`."""
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
            helper = "call_nested" if nested else "call_at"
            return f"{helper}({self.const(t.func)}, {args}, {self.const(t)})"
        return self.const(t)

    def value(self, target: str, t) -> None:
        """Emit ``target = t``. Its calls are made directly, in one ``try``:
        every value met here is ground (a known variable is bound to a ground
        term, a function's value is ground), so :func:`call_nested` would
        never keep a call as a term. Only when a call fails is the term
        computed again through :func:`call_at`, which places the error at the
        failing call (as ``compile._fast_path`` does)."""
        if not has_call(t):
            self.emit(f"{target} = {self.term(t)}")
            return
        fast = self.term(t, direct=True)
        slow = self.term(t)
        self.emit("try:")
        self.emit(f"    {target} = {fast}")
        self.emit("except HtnError:")
        self.emit(f"    {target} = {slow}")

    def factory(self, what: str = "conjunction"):
        """The code's factory ``make(*constants) -> run``, or None when this
        mode gains nothing (every conjunct would take the general path).
        ``what`` names the code (see :mod:`~htn.jshop.logic.codegen`)."""
        lits = self.lits
        if all(
            lit.kind == GENERAL
            or (lit.kind == ASSIGN and not term_vars(lit.expr.term, set()) <= self.known)
            for lit in lits
        ):
            return None
        for v in sorted(self.entry & set().union(*(lit.vars for lit in lits))):
            self.emit(f"x{v} = env[{v}]")
        for k in range(len(lits)):
            if k and self.loops >= NESTED_CONJUNCTS:
                self.hand_off(k)  # Python nests at most 20 loops
                break
            if not self.literal(k):
                break
        else:
            self.finish()
        if self.loops > NESTED_CONJUNCTS:
            return None
        params = []
        for k in range(len(lits)):
            params += [f"L{k}", f"M{k}", f"H{k}", f"G{k}", f"R{k}", f"X{k}"]
        src = [
            f"def make({', '.join(params)}):",
            *("    " + line for line in self.pre),
            "    def run(env):",
            *self.lines,
            "    return run",
        ]
        define("\n".join(src), what, self.ns)
        return self.ns["make"]

    def hand_off(self, k: int) -> None:
        """Conjuncts ``k..`` asked of the rest's own conjunction (``R{k-1}``,
        compiled per binding mode in its turn), with the binding so far."""
        self.emit(f"yield from R{k - 1}({self.binding(k)})")

    def binding(self, k: int) -> str:
        """The binding list so far, as of conjunct ``k``: ``base``, or a copy
        of it named ``e{k}`` with the variables held in locals written in."""
        if not self.local:
            return self.base
        self.emit(f"e{k} = {self.base}[:]")
        for v in sorted(self.local):
            self.emit(f"e{k}[{v}] = x{v}")
        return f"e{k}"

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
        if (
            kind == ASSIGN
            and lit.expr.var.index not in self.known
            and not term_vars(lit.expr.term, set()) <= self.known
        ):
            kind = GENERAL
        if kind == ATOM or kind == NOT_ATOM:
            self.atom(k, lit, kind == NOT_ATOM)
        elif kind == NOT_AXIOM:
            ground = all(type(a) is not Var or a.index in self.known for a in lit.args)
            self.emit(f"if next(L{k}({self.bound(lit.args)}, env, {ground}), None) is None:")
            self.depth += 1
        elif kind == AXIOM:
            ground = all(type(a) is not Var or a.index in self.known for a in lit.args)
            return self.general(k, lit, f"L{k}({self.bound(lit.args)}, {{}}, {ground})")
        elif kind == CALL and not lit.vars <= self.known:
            # a call with a free variable stays a term, which is not nil: the
            # conjunct holds, once the calls inside it that can be evaluated
            # have been (they may fail), as ``subst`` evaluates them
            self.inner_calls(lit.expr.call)
        elif kind == CALL:
            self.value(f"v{k}", lit.expr.call)
            self.emit(f"if not (type(v{k}) is tuple and not v{k}):")
            self.depth += 1
        elif kind == ASSIGN:
            v = lit.expr.var.index
            if v not in self.known:  # an earlier binding wins, as in JSHOP2
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
        if tt is CallTerm and term_vars(t, set()) <= self.known:
            self.emit(self.term(t))
        elif tt is CallTerm or tt is tuple:
            for x in t.args if tt is CallTerm else t:
                self.inner_calls(x)

    def atom(self, k: int, lit: Literal, negated: bool) -> None:
        args = lit.args
        if lit.vars <= self.known:
            tup = self.term(args)
            if negated:
                test = f"{tup} not in M{k}"
                if lit.facts:
                    test += f" and {tup} not in H{k}[1]"
                self.emit(f"if {test}:")
            elif lit.facts:  # a ground fact may be stated more than once
                self.emit(f"t{k} = {tup}")
                self.emit(f"for _ in range((t{k} in M{k}) + H{k}[1].get(t{k}, 0)):")
                self.loops += 1
            else:
                self.emit(f"if {tup} in M{k}:")
            self.depth += 1
            return
        conds = [f"len(t) == {len(args)}"] if self.sized[k] else []
        binds: list = []
        first: dict = {}  # variable -> where it is first met in ``t``
        source = f"chain(L{k}, H{k}[0])" if lit.facts else f"L{k}"
        at = self.index_places(lit)
        if at:  # the atoms that agree at the bound places, in the state's order
            conds = []
            self.pre.append(f"I{k} = X{k}({len(args)}, {tuple(at)!r})")
            source = f"I{k}.get({self.term(tuple(args[i] for i in at))}, ())"
        for i, a in enumerate(args):
            if i in at:
                continue
            if type(a) is tuple and a and not term_vars(a, set()) <= self.known:
                # a list with a free variable: its shape, then element by element
                conds.append(f"type(t[{i}]) is tuple and len(t[{i}]) == {len(a)}")
                for j, x in enumerate(a):
                    self.match(f"t[{i}][{j}]", x, conds, binds, first)
            else:
                self.match(f"t[{i}]", a, conds, binds, first)
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

    def index_places(self, lit: Literal) -> list:
        """The places of ``lit``'s bound arguments, where the state is frozen
        and every argument is a symbol, a number or a variable (else [],
        and the atoms are scanned)."""
        if not self.indexed or lit.facts:
            return []
        args = lit.args
        if not all(type(a) in (str, float, Var) for a in args):
            return []
        return [i for i, a in enumerate(args) if type(a) is not Var or a.index in self.known]

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
        return (
            "("
            + "".join(
                (f"x{a.index}" if type(a) is Var and a.index in self.known else self.const(a))
                + ", "
                for a in args
            )
            + ")"
        )

    def general(self, k: int, lit: Literal, call: str = "G{k}({})") -> bool:
        """Conjunct ``k`` asked of the general engine (``call`` names the
        satisfier, ``{}`` standing for the binding list)."""
        call = call.replace("{k}", str(k))
        arg = self.binding(k)
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
            ground = " and ".join(
                f"(type(x{v}) is str or type(x{v}) is float or "
                f"(x{v} is not None and is_ground(x{v})))"
                for v in new
            )
            self.emit(f"if not ({ground}):")
            self.emit(f"    yield from R{k}(b{k})")
            self.emit("    continue")
            self.known |= set(new)
        return True
