"""Compile argument tuples of the domain into fast Python functions.

JSHOP2 compiles a domain to Java for speed (manual section 4); we do the same
on a small scale for the two hottest operations on argument tuples:

* :func:`binder` - apply a binding to a tuple of terms (``subst``), and
* :func:`head_unifier` - unify a method's or operator's head with a task

(method bodies are bound by :mod:`htn.jshop.logic.task_lists`).

Only "flat" tuples (constants and variables) are compiled; anything with a
nested list or call term uses the generic functions in :mod:`htn.jshop.language.terms`, so
the semantics are exactly those of ``subst`` and ``unify``.

The shape of the generated source never follows the nesting of the input:
Python's compiler refuses more than 20 nested blocks, 200 nested parentheses
or a few thousand chained operators, and domains may have many conjuncts,
deeply nested list terms or atoms with many arguments. Long chains are split
into statements, long conjunctions run on an explicit stack, and list terms
nested deeper than :data:`FAST_PATH_DEPTH` take the generic path.
"""

from __future__ import annotations

from collections.abc import Callable

from htn.jshop.language.errors import HtnError
from htn.jshop.language.terms import CallTerm, Var, is_ground, source_str, subst, unify

from .caches import cache
from .codegen import define


def flat_args(args: tuple) -> bool:
    return all(type(a) in (str, float, Var) for a in args)


_BINDERS = cache()
_UNIFIERS = cache()


def _shown(args: tuple) -> str:
    """Terms as the source writes them, for the names of generated code."""
    return "(" + " ".join(source_str(a) for a in args) + ")"


def binder(args: tuple, what: str | None = None) -> Callable[[list], tuple]:
    """Cached :func:`make_binder` (keyed by the domain's own tuple object);
    ``what`` names the generated code (see :mod:`~htn.jshop.logic.codegen`)."""
    return _BINDERS.make(args, lambda: make_binder(args, what))


_SUBSTITUTERS = cache()


def substituter(args: tuple, what: str | None = None) -> Callable[[list], tuple]:
    """``env -> subst(args, env)`` (the binder's tuple without its key), for
    the places that only build a term: effects, task atoms, plan steps. A
    tuple of symbols, numbers and variables needs no groundness test."""
    fn = _SUBSTITUTERS.get(args)
    if fn is None:
        if flat_args(args):
            ns: dict = {}
            parts = []
            for i, a in enumerate(args):
                if type(a) is Var:
                    ns[f"v{i}"] = a
                    parts.append(f"(env[{a.index}] if env[{a.index}] is not None else v{i})")
                else:
                    ns[f"c{i}"] = a
                    parts.append(f"c{i}")
            define(
                f"def sub(env):\n    return ({''.join(p + ', ' for p in parts)})",
                what or f"substitution into {_shown(args)}",
                ns,
            )
            fn = ns["sub"]
        else:
            bind = binder(args, what)

            def fn(env, bind=bind):
                return bind(env)[1]

        _SUBSTITUTERS.put(args, fn)
    return fn


def head_unifier(head: tuple, what: str | None = None) -> Callable[[tuple, list], bool]:
    """Cached :func:`make_head_unifier`."""
    return _UNIFIERS.make(head, lambda: make_head_unifier(head, what))


GENERIC = 1 << 30  # a scan key meaning "use the generic scanner"


def make_binder(args: tuple, what: str | None = None) -> Callable[[list], tuple]:
    """A function ``env -> (key, bound_args)`` equivalent to ``subst``.

    ``key`` is None when the result is ground (the caller can then look the
    atom up in the state's hash set). Otherwise it tells :func:`scanner` which
    variables are unbound: bit j is set when the j-th distinct variable of
    ``args`` is unbound; ``GENERIC`` or more when some element is bound to a
    non-ground term, which needs full unification.
    """
    if not args:
        return lambda env: (None, ())
    consts = {}
    parts = []  # expression of each element, bound
    unbound = []  # same, but keeping unbound variables
    tests = []  # groundness test of each non-constant element
    keys = []  # key contribution of each non-constant element
    lines = []
    seen: set = set()
    for i, a in enumerate(args):
        ta = type(a)
        if ta is Var:
            name = f"x{a.index}"
            if a.index not in seen:
                bit = 1 << len(seen)
                seen.add(a.index)
                consts[f"v{a.index}"] = a
                lines.append(f"    {name} = env[{a.index}]")
                lines.append(
                    f"    g{a.index} = {name} is not None and (type({name}) is str or "
                    f"type({name}) is float or is_ground({name}))"
                )
                tests.append(f"g{a.index}")
                keys.append(f"(0 if g{a.index} else {bit} if {name} is None else GENERIC)")
            parts.append(name)
            unbound.append(f"({name} if {name} is not None else v{a.index})")
        elif ta is str or ta is float or (ta is tuple and not a):
            consts[f"c{i}"] = a
            parts.append(f"c{i}")
            unbound.append(f"c{i}")
        elif ta is tuple and flat_args(a):
            # a flat list such as (on ?x ?z): built inline, without subst
            inner, inner_unbound, inner_tests = [], [], []
            for j, x in enumerate(a):
                if type(x) is Var:
                    name = f"x{x.index}"
                    consts[f"v{x.index}"] = x
                    lines.append(f"    {name} = env[{x.index}]")
                    inner_tests.append(
                        f"({name} is not None and (type({name}) is str or "
                        f"type({name}) is float or is_ground({name})))"
                    )
                    inner.append(name)
                    inner_unbound.append(f"({name} if {name} is not None else v{x.index})")
                else:
                    consts[f"c{i}_{j}"] = x
                    inner.append(f"c{i}_{j}")
                    inner_unbound.append(f"c{i}_{j}")
            lines.append(f"    h{i} = {' and '.join(inner_tests) or 'True'}")
            tests.append(f"h{i}")
            keys.append(f"(0 if h{i} else GENERIC)")
            parts.append("(" + "".join(x + ", " for x in inner) + ")")
            unbound.append("(" + "".join(x + ", " for x in inner_unbound) + ")")
        else:  # nested list or call term: the generic substitution
            consts[f"c{i}"] = a
            lines.append(f"    y{i} = subst(c{i}, env)")
            lines.append(f"    h{i} = is_ground(y{i})")
            tests.append(f"h{i}")
            keys.append(f"(0 if h{i} else GENERIC)")
            parts.append(f"y{i}")
            unbound.append(f"y{i}")
    if not tests:
        return lambda env: (None, args)
    fast = _fast_path(args, consts)
    src = [
        "def bind(env):",
        *fast,
        *lines,
        f"    if {' and '.join(tests)}:",
        f"        return None, ({', '.join(parts)},)",
        *_or_lines("key", keys),
        f"    return key, ({', '.join(unbound)},)",
    ]
    ns = dict(consts, is_ground=is_ground, subst=subst, GENERIC=GENERIC)
    define("\n".join(src), what or f"binding of {_shown(args)}", ns)
    return ns["bind"]


def _or_lines(name: str, exprs: list, chunk: int = 32) -> list:
    """``name = e1 | e2 | ...`` as statements of at most ``chunk`` operands:
    one long chain of ``|`` nests as deep as it is long in Python's parser."""
    lines = []
    for k in range(0, len(exprs), chunk):
        op = "=" if k == 0 else "|="
        lines.append(f"    {name} {op} {' | '.join(exprs[k : k + chunk])}")
    return lines


FAST_PATH_DEPTH = 16  # list terms nested deeper than this use the generic subst


def _depth(args: tuple) -> int:
    """How deeply list and call terms nest in ``args`` (iteratively)."""
    deepest = 0
    stack = [(a, 1) for a in args]
    while stack:
        t, d = stack.pop()
        tt = type(t)
        if tt is tuple:
            stack.extend((x, d + 1) for x in t)
        elif tt is CallTerm:
            stack.extend((x, d + 1) for x in t.args)
        else:
            continue
        deepest = max(deepest, d)
    return deepest


def _fast_path(args: tuple, ns: dict) -> list:
    """Source lines returning at once when every variable of ``args`` (call
    arguments and nested lists included) is bound to a symbol, a number or nil:
    then every call can be evaluated inline and the result is ground.

    If a call fails, the generated code falls through to the general code,
    whose ``subst`` evaluates again and reports the failing call's place."""
    if all(type(a) in (str, float, Var) for a in args):
        return []  # flat tuples are already handled well by the general code
    if _depth(args) > FAST_PATH_DEPTH:
        return []
    seen: dict = {}
    counter = [0]

    def expr(t):
        tt = type(t)
        if tt is Var:
            seen[t.index] = None
            return f"f{t.index}"
        if tt is str or tt is float:
            name = f"k{counter[0]}"
            counter[0] += 1
            ns[name] = t
            return name
        if tt is tuple:
            return "(" + "".join(expr(x) + ", " for x in t) + ")"
        if tt is CallTerm:
            name = f"fn{counter[0]}"
            counter[0] += 1
            ns[name] = t.func
            return f"{name}((" + "".join(expr(x) + ", " for x in t.args) + "))"
        raise _NoFastPath

    try:
        body = "(" + "".join(expr(a) + ", " for a in args) + ")"
    except _NoFastPath:
        return []
    lines = [f"    f{i} = env[{i}]" for i in seen]
    test = (
        " and ".join(f"(type(f{i}) is str or type(f{i}) is float or f{i} == ())" for i in seen)
        or "True"
    )
    ns["HtnError"] = HtnError
    return lines + [
        f"    if {test}:",
        "        try:",
        f"            return None, {body}",
        "        except HtnError:",
        "            pass",
    ]


class _NoFastPath(Exception):
    pass


def make_scanner(args: tuple, key: int, what: str | None = None) -> Callable:
    """A generator ``(atoms, bound, env) -> envs`` matching ``args`` whose
    unbound variables are those of ``key`` (see :func:`make_binder`) against a
    live list of atoms, in order; equivalent to unifying element by element."""
    n = len(args)
    conds = [f"len(a) == {n}"]
    pre = []
    assigns = []
    first_pos: dict = {}
    distinct = 0
    for i, a in enumerate(args):
        if type(a) is Var:
            if a.index not in first_pos:
                first_pos[a.index] = i
                unbound = key & (1 << distinct)
                distinct += 1
                if unbound:
                    assigns.append(f"new[{a.index}] = a[{i}]")
                    continue
            elif key & (1 << list(first_pos).index(a.index)):
                conds.append(f"a[{i}] == a[{first_pos[a.index]}]")
                continue
        pre.append(f"    b{i} = bound[{i}]")
        conds.append(f"a[{i}] == b{i}")
    src = [
        "def scan(lst, bound, env):",
        *pre,
        "    for a in lst:",
        f"        if {' and '.join(conds)}:",
        "            new = env[:]",
        *[f"            {x}" for x in assigns],
        "            yield new",
    ]
    ns: dict = {}
    define("\n".join(src), f"{what or 'atoms matching ' + _shown(args)} (unbound: {key:b})", ns)
    return ns["scan"]


_SCANNERS = cache()
_TERMS = cache()
_CONJUNCTIONS: dict = {}


def term_binder(term, what: str | None = None) -> Callable[[list], tuple]:
    """Cached binder of a single term (keyed by the term object itself)."""
    return _TERMS.make(term, lambda: make_binder((term,), what))


NESTED_CONJUNCTS = 16  # Python allows 20 nested blocks; longer conjunctions use a stack


def conjunction(sats: list) -> Callable:
    """Left-to-right backtracking over conjuncts as one generator of nested
    loops (JSHOP2's generated conjunction classes do the same). The code is
    generated once per number of conjuncts, up to :data:`NESTED_CONJUNCTS`;
    longer conjunctions backtrack over an explicit stack of generators, in
    the same order."""
    n = len(sats)
    if n > NESTED_CONJUNCTS:
        return _stacked_conjunction(sats)
    make = _CONJUNCTIONS.get(n)
    if make is None:
        args = ", ".join(f"s{i}" for i in range(n))
        lines = [f"def make({args}):", "    def conj(env):"]
        for i in range(n - 1):
            lines.append("    " * (i + 2) + f"for e{i + 1} in s{i}(e{i}):")
        lines.append("    " * (n + 1) + f"yield from s{n - 1}(e{n - 1})")
        lines.append("    return conj")
        ns: dict = {}
        define("\n".join(lines).replace("(e0)", "(env)"), f"conjunction of {n} conjuncts", ns)
        make = _CONJUNCTIONS[n] = ns["make"]
    return make(*sats)


def _stacked_conjunction(sats: list) -> Callable:
    """The satisfiers of ``sats`` in conjunction, depth first, with one open
    generator per conjunct on a list instead of one nested loop each."""
    last = len(sats) - 1

    def conj(env):
        open_ = [sats[0](env)]
        while open_:
            for e in open_[-1]:
                if len(open_) > last:
                    yield e
                else:
                    open_.append(sats[len(open_)](e))
                    break
            else:
                open_.pop()

    return conj


def scanner(args: tuple, key: int, what: str | None = None) -> Callable:
    """Cached :func:`make_scanner`."""
    return _SCANNERS.make(args, lambda: make_scanner(args, key, what), (id(args), key))


def make_head_unifier(head: tuple, what: str | None = None) -> Callable[[tuple, list], bool]:
    """A function ``(task_args, env) -> bool`` equivalent to unifying each
    head term with the task's term (a variable in the task binds nothing)."""
    n = len(head)
    if not all(type(a) in (str, float, Var) for a in head):

        def generic(args, env, head=head, n=n):
            if len(args) != n:
                return False
            for p, t in zip(head, args):
                if not unify(p, t, env):
                    return False
            return True

        return generic
    ns: dict = {"Var": Var, "is_ground": is_ground}
    src = ["def unify_head(args, env):", f"    if len(args) != {n}:", "        return False"]
    seen = set()
    # a task argument binds a head variable only if it is ground (see terms.unify)
    known = "(type(t) is str or type(t) is float or (type(t) is not Var and is_ground(t)))"
    for i, a in enumerate(head):
        src.append(f"    t = args[{i}]")
        if type(a) is Var:
            if a.index not in seen:
                seen.add(a.index)
                src.append(f"    if {known}: env[{a.index}] = t")
            else:
                src += [
                    f"    if {known}:",
                    f"        v = env[{a.index}]",
                    f"        if v is None: env[{a.index}] = t",
                    "        elif not (v == t and type(v) is type(t)): return False",
                ]
        else:
            ns[f"c{i}"] = a
            src.append(
                f"    if type(t) is not Var and not (type(t) is type(c{i}) and t == c{i}):"
                " return False"
            )
    src.append("    return True")
    define("\n".join(src), what or f"unifier of the head {_shown(head)}", ns)
    return ns["unify_head"]
