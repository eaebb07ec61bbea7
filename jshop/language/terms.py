"""Terms of the JSHOP2 language (manual section 3.2) and one-way unification.

Representation, chosen so that ground terms are plain hashable Python values:

* a constant symbol is a lower-case ``str``;
* a number is a ``float`` (JSHOP2 keeps every number as a Java double);
* a proper list term is a ``tuple`` of terms; ``NIL`` (the empty list) is ``()``;
* an improper (dotted) list ``(a b . c)`` is a :class:`Dotted`, always
  normalised so that its tail is not itself a list;
* a variable symbol is a :class:`Var`, numbered within its domain element
  (manual 5.1.1: the scope of a variable is its method, operator or axiom);
* a call term ``(call f t1 .. tn)`` is a :class:`CallTerm`; it is replaced by
  its value as soon as its arguments are ground (manual 3.2.2).

Unification follows JSHOP2's ``findUnifier``: it is one-way. Variables of the
pattern get bound; a variable on the other side matches anything and binds
nothing, which is why bindings propagate only downwards in the task network.
A list term that still holds variables, such as ``(a ?w)`` passed down in a
task, is treated the same way when a pattern variable meets it: its variables
belong to another domain element (their indices mean nothing in this
element's binding), so binding them in would be meaningless - JSHOP2 indexes
the wrong binding there and fails.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

from .errors import HtnError, PlanningError

if TYPE_CHECKING:
    from .errors import Place

NIL: tuple[Any, ...] = ()


class Var:
    """A variable symbol; ``index`` is its slot in the element's binding."""

    __slots__ = ("name", "index")

    def __init__(self, name: str, index: int = -1) -> None:
        self.name = name
        self.index = index

    def __repr__(self) -> str:
        return f"Var({self.name!r}, {self.index})"


class Dotted:
    """An improper list ``(i1 .. in . tail)`` whose tail is not a list."""

    __slots__ = ("items", "tail", "_hash")

    def __init__(self, items: tuple[Any, ...], tail: Any) -> None:
        self.items = items
        self.tail = tail
        self._hash: int | None = None

    def __eq__(self, other: object) -> bool:
        return type(other) is Dotted and self.items == other.items and self.tail == other.tail

    def __hash__(self) -> int:
        if self._hash is None:
            self._hash = hash(
                (self.items, "."),
            ) ^ hash(self.tail)
        return self._hash

    def __repr__(self) -> str:
        return f"Dotted({self.items!r}, {self.tail!r})"


def make_list(items: Sequence[Any], tail: Any = NIL) -> Any:
    """Build the list term ``(items . tail)``, normalising nested tails."""
    items = tuple(items)
    if type(tail) is tuple:
        return items + tail
    if type(tail) is Dotted:
        return Dotted(items + tail.items, tail.tail)
    if not items:
        return tail
    return Dotted(items, tail)


class CallTerm:
    """``(call f args..)``: ``func`` maps a tuple of ground terms to a term."""

    __slots__ = ("name", "func", "args", "pos")

    def __init__(
        self,
        name: str,
        func: Callable[[tuple[Any, ...]], Any],
        args: tuple[Any, ...],
        pos: Place | None = None,
    ) -> None:
        self.name = name
        self.func = func
        self.args = args
        self.pos = pos

    def __repr__(self) -> str:
        return f"CallTerm({self.name!r}, {self.args!r})"


def at_call(exc: HtnError, call: CallTerm) -> HtnError:
    """``exc`` placed at ``call`` in the domain, unless it has a place already
    (an error in a standard function given a symbol, or in a user function)."""
    if exc.file is None and call.pos is not None:
        exc.file, exc.line, exc.col = call.pos.file, call.pos.line, call.pos.col
    elif getattr(exc, "in_user_code", False) and call.pos is not None:
        exc.in_user_code = False  # placed at the user's line; say where it was called
        exc.message += f" (called at {call.pos.file}:{call.pos.line}:{call.pos.col})"
    return exc


def is_ground(t: Any) -> bool:
    tt = type(t)
    if tt is str or tt is float:
        return True
    if tt is tuple:
        for x in t:
            tx = type(x)  # symbols and numbers without a call: most atoms
            if tx is not str and tx is not float and not is_ground(x):
                return False
        return True
    if tt is Dotted:
        return is_ground(t.items) and is_ground(t.tail)
    return False  # Var or an unevaluated CallTerm


def subst(t: Any, env: list[Any]) -> Any:
    """Apply a binding to a term, evaluating call terms that became ground."""
    tt = type(t)
    if tt is str or tt is float:
        return t
    if tt is Var:
        v = env[t.index]
        return t if v is None else v
    if tt is tuple:
        return tuple([subst(x, env) for x in t])
    if tt is CallTerm:
        args = tuple([subst(x, env) for x in t.args])
        if is_ground(args):
            try:
                return t.func(args)
            except HtnError as exc:
                raise at_call(exc, t) from exc
        return CallTerm(t.name, t.func, args, t.pos)
    if tt is Dotted:
        return make_list([subst(x, env) for x in t.items], subst(t.tail, env))
    return t


def unify(p: Any, t: Any, env: list[Any]) -> bool:
    """Extend ``env`` (in place) so that pattern ``p`` matches term ``t``.

    Mirrors JSHOP2's ``Term.findUnifier``: a variable in ``t`` matches
    anything and binds nothing; a bound pattern variable must equal ``t``.
    """
    tp = type(p)
    if tp is Var:
        tt = type(t)
        if tt is Var or (tt is not str and tt is not float and not is_ground(t)):
            return True
        v = env[p.index]
        if v is None:
            env[p.index] = t
            return True
        return v == t and type(v) is type(t)
    tt = type(t)
    if tt is Var:
        return True
    if tp is str:
        return tt is str and p == t
    if tp is float:
        return tt is float and p == t
    if tp is tuple:
        if tt is tuple:
            if len(p) != len(t):
                return False
            for a, b in zip(p, t):
                if not unify(a, b, env):
                    return False
            return True
        if tt is Dotted:
            return _unify_dotted(Dotted(p, NIL), t, env)
        return False
    if tp is Dotted:
        if tt is tuple or tt is Dotted:
            return _unify_dotted(p, t, env)
        return False
    if tp is CallTerm:
        v = subst(p, env)
        if type(v) is CallTerm:
            return False
        return unify(v, t, env)
    return False


def _unify_dotted(p: Dotted, t: Any, env: list[Any]) -> bool:
    """Unify cons by cons, as JSHOP2's ``List.findUnifierList`` does."""
    pi, pt = p.items, p.tail
    ti: tuple[Any, ...]
    tt_: Any
    if type(t) is tuple:
        ti, tt_ = t, NIL
    else:
        ti, tt_ = t.items, t.tail
    n = len(pi)
    for k in range(n):
        if k >= len(ti):
            # the rest of t is its tail: a variable matches, anything else fails
            if type(tt_) is Var:
                return True
            return False
        if not unify(pi[k], ti[k], env):
            return False
    rest = make_list(ti[n:], tt_)
    return unify(pt, rest, env)


# --------------------------------------------------------------- printing


def java_double(x: float) -> str:
    """Format a float as Java's ``String.valueOf(double)`` does.

    Uses Python's shortest round-trip digits; JDK 17's algorithm can print a
    longer digit string for a few rare values (fixed in JDK 19), which is a
    known, documented deviation.
    """
    if x != x:
        return "NaN"
    if x in (float("inf"), float("-inf")):
        return "Infinity" if x > 0 else "-Infinity"
    if x == 0.0:
        return "-0.0" if str(x).startswith("-") else "0.0"
    a = abs(x)
    if a < 1e7 and a >= 1.0 and x.is_integer():  # the common case, printed fast
        return f"{int(x)}.0"
    if 1e-3 <= a < 1e7:
        s = repr(x)
        if "e" in s or "E" in s:  # repr switches to exponent form at 1e16 only
            s = f"{x:.17f}".rstrip("0")
        if "." not in s:
            s += ".0"
        if s.endswith("."):
            s += "0"
        return s
    digits, exp = _shortest_digits(a)
    mant = digits[0] + "." + (digits[1:] or "0")
    return ("-" if x < 0 else "") + f"{mant}E{exp}"


def _shortest_digits(a: float) -> tuple[str, int]:
    s = f"{a:.17e}"
    # find the shortest precision that round-trips
    for prec in range(0, 18):
        cand = f"{a:.{prec}e}"
        if float(cand) == a:
            s = cand
            break
    mant, exp = s.split("e")
    digits = mant.replace(".", "").rstrip("0") or "0"
    return digits, int(exp)


def term_str(t: Any) -> str:
    """Print a term exactly as JSHOP2's ``toString`` does."""
    tt = type(t)
    if tt is str:
        symbol: str = t
        return symbol
    if tt is float:
        return java_double(t)
    if tt is tuple:
        if not t:
            return "NIL"
        return "(" + " ".join([term_str(x) for x in t]) + ")"
    if tt is Dotted:
        return "(" + " ".join([term_str(x) for x in t.items]) + " . " + term_str(t.tail) + ")"
    if tt is Var:
        return f"VAR{t.index}"
    if tt is CallTerm:
        inner = " ".join([term_str(x) for x in t.args])
        return f"(CALL {t.name} {inner})" if inner else f"(CALL {t.name})"
    return str(t)


SHOWN_TERM = 200  # characters of a term quoted in a message


def shown_term(t: Any, limit: int = SHOWN_TERM) -> str:
    """``term_str(t)`` for a message: cut to about ``limit`` characters
    (``...`` where the rest is left out), in time that grows with ``limit``,
    not with the term (a list of millions of elements is quoted at once)."""
    out: list[str] = []
    size = 0
    stack = [t]
    while stack and size <= limit:
        x = stack.pop()
        tx = type(x)
        if tx is _Text:
            piece = x.text
        elif tx is tuple:
            if not x:
                piece = "NIL"
            else:
                piece = "("
                stack.append(_CLOSE)
                # only as many elements as can still be shown are looked at
                items = x[: limit - size + 1]
                if len(items) < len(x):
                    stack.append(_MORE)
                for i in range(len(items) - 1, -1, -1):
                    stack.append(items[i])
                    if i:
                        stack.append(_SPACE)
        elif tx is Dotted:
            stack.extend([_CLOSE, x.tail, _Text(" . ")])
            items = x.items[:limit]
            for i in range(len(items) - 1, -1, -1):
                stack.append(items[i])
                if i:
                    stack.append(_SPACE)
            piece = "("
        elif tx is CallTerm:
            stack.append(_CLOSE)
            for a in reversed(x.args[:limit]):
                stack.append(a)
                stack.append(_SPACE)
            piece = f"(CALL {x.name}"
        elif tx is str or tx is float or tx is Var:
            piece = term_str(x)
        else:
            piece = str(x)
        if len(piece) > limit:
            piece = piece[:limit]
        out.append(piece)
        size += len(piece)
    text = "".join(out)
    if stack or len(text) > limit:
        return text[: max(limit - 3, 0)] + "..."
    return text


class _Text:
    __slots__ = ("text",)

    def __init__(self, text: str) -> None:
        self.text = text


_CLOSE, _SPACE, _MORE = _Text(")"), _Text(" "), _Text(" ...")


def atom_str(name: str, args: Sequence[Any]) -> str:
    """Print a predicate or task instance: ``(name a1 .. an)``."""
    if not args:
        return f"({name})"
    return "(" + name + " " + " ".join([term_str(a) for a in args]) + ")"


def source_str(t: Any) -> str:
    """Print a term as JSHOP2 source text (variables by name)."""
    tt = type(t)
    if tt is Var:
        name: str = t.name
        return name
    if tt is tuple:
        return "(" + " ".join(source_str(x) for x in t) + ")" if t else "nil"
    if tt is Dotted:
        return "(" + " ".join(source_str(x) for x in t.items) + " . " + source_str(t.tail) + ")"
    if tt is CallTerm:
        return "(call " + " ".join([t.name] + [source_str(x) for x in t.args]) + ")"
    return term_str(t)


def source_atom(name: str, args: Sequence[Any]) -> str:
    """Print a predicate or task as JSHOP2 source text: ``(name ?x a)``."""
    return "(" + " ".join([name, *[source_str(a) for a in args]]) + ")"


def variables(t: Any, out: list[Var]) -> list[Var]:
    """Append the variable occurrences of ``t`` to ``out`` in textual order."""
    tt = type(t)
    if tt is Var:
        out.append(t)
    elif tt is tuple:
        for x in t:
            variables(x, out)
    elif tt is Dotted:
        for x in t.items:
            variables(x, out)
        variables(t.tail, out)
    elif tt is CallTerm:
        for x in t.args:
            variables(x, out)
    return out


def atom_from_term(t: Any, pos: Place | None) -> tuple[str, tuple[Any, ...]]:
    """A list term ``(p a1 .. an)`` used as an atom (manual 3.14)."""
    if type(t) is tuple and t and type(t[0]) is str:
        return t[0], t[1:]
    raise PlanningError.at(
        pos, f"a variable used as an atom is bound to {shown_term(t)}, which is not an atom"
    )
