"""When generated code is compiled: after its interpreted equivalent has
answered :data:`WARM` calls, as a tiered JIT compiles only hot code.

Compiling costs far more than running a piece once (Python compiles about a
microsecond per character of source, a binder or a head unifier a few hundred
characters), and a small search runs most pieces a few times only: Childsnack
p05 reduces each of its tasks about a dozen times. So every piece starts
*warming*: an interpreted equivalent (``subst``, ``unify``, ``scan_atoms``,
the task list built term by term) answers its first calls, and the piece is
compiled at its :data:`WARM`-th call and put where its callers find it
(``install``). A piece compiled once is reused by every later planner of the
domain (the caches of :mod:`~htn.jshop.logic.compile`), from its first call.

Each interpreted equivalent computes exactly what the compiled code computes
(the compiled code's docstrings say "equivalent to subst/unify"), so when
the switch happens changes the speed only, never a result or its order.
"""

from __future__ import annotations

from collections.abc import Callable

from htn.jshop.language.terms import Var, is_ground, subst, unify

from . import compile as C
from .caches import cache
from .scan import scan_atoms

# Calls answered by the interpreted equivalent before compiling: a compiled
# piece saves a few microseconds a call and costs some hundred to compile,
# so it pays after a few dozen calls (on Depots p06 the cold search took 27M
# instructions with 16, 22M with 32).
WARM = 32


def warming(slow: Callable, compile_fast: Callable, install: Callable, piece, kind="") -> Callable:
    """``slow``, counting the calls of ``piece`` (a domain object, and the
    ``kind`` of code made of it: the count is the process's, over all
    planners): the :data:`WARM`-th call also compiles the fast equivalent
    (``compile_fast()``) and hands it to ``install``, which puts it where the
    callers find it from then on."""
    count = calls(piece, kind)

    def warm(*args):
        count[1] += 1
        if count[1] >= WARM:
            install(compile_fast())
        return slow(*args)

    return warm


_CALLS = cache()  # (id(piece), kind) -> [piece, calls]


def calls(piece, kind="") -> list:
    """``[piece, calls so far]``, the process's count of a piece's calls."""
    return _CALLS.make(piece, lambda: [piece, 0], (id(piece), kind))


def binder(args: tuple, what: Callable, install: Callable) -> Callable:
    """:func:`~htn.jshop.logic.compile.binder`, warming. The interpreted
    binder returns the key ``GENERIC`` for any pattern that is not ground,
    which asks for the general matcher (``scan_atoms``)."""
    fast = C._BINDERS.get(args)
    if fast is not None:
        return fast

    if C.flat_args(args):
        slots = [(i, a.index) for i, a in enumerate(args) if type(a) is Var]

        def bind(env):
            b = list(args)
            ground = True
            for i, k in slots:
                v = env[k]
                if v is None:
                    ground = False
                else:
                    b[i] = v
                    if ground and type(v) is not str and type(v) is not float:
                        ground = is_ground(v)
            return (None if ground else C.GENERIC), tuple(b)
    else:

        def bind(env):
            b = subst(args, env)
            return (None, b) if is_ground(b) else (C.GENERIC, b)

    return warming(bind, lambda: C.binder(args, what()), install, args, "bind")


def term_binder(term, what: Callable, install: Callable) -> Callable:
    """:func:`~htn.jshop.logic.compile.term_binder`, warming."""
    fast = C._TERMS.get(term)
    if fast is not None:
        return fast
    return warming(
        lambda env: (None, (subst(term, env),)),
        lambda: C.term_binder(term, what()),
        install,
        term,
        "term",
    )


def scanner(args: tuple, key: int, what: Callable, install: Callable) -> Callable:
    """:func:`~htn.jshop.logic.compile.scanner`, warming (``scan_atoms``)."""
    fast = C._SCANNERS.get(args, (id(args), key))
    if fast is not None:
        return fast
    return warming(scan_atoms, lambda: C.scanner(args, key, what()), install, args, key)


def substituter(args: tuple, what: Callable, install: Callable) -> Callable:
    """:func:`~htn.jshop.logic.compile.substituter`, warming."""
    fast = C._SUBSTITUTERS.get(args)
    if fast is not None:
        return fast
    return warming(
        interpreted_substitution(args), lambda: C.substituter(args, what()), install, args, "subst"
    )


def interpreted_substitution(args: tuple) -> Callable[[list], tuple]:
    """``env -> subst(args, env)``, element by element for a flat tuple
    (symbols, numbers, variables: no call needed per element)."""
    if not C.flat_args(args):
        return lambda env: subst(args, env)
    slots = [(i, a.index) for i, a in enumerate(args) if type(a) is Var]

    def sub(env):
        b = list(args)
        for i, k in slots:
            v = env[k]
            if v is not None:
                b[i] = v
        return tuple(b)

    return sub


def head_unifier(head: tuple, what: Callable, install: Callable) -> Callable:
    """:func:`~htn.jshop.logic.compile.head_unifier`, warming."""
    fast = C._UNIFIERS.get(head)
    if fast is not None:
        return fast
    n = len(head)

    def unify_head(args, env):
        if len(args) != n:
            return False
        for p, t in zip(head, args):
            if not unify(p, t, env):
                return False
        return True

    return warming(unify_head, lambda: C.head_unifier(head, what()), install, head, "head")
