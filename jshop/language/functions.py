"""Functions callable with ``(call f ...)``: JSHOP2's standard library (manual
appendix A) and user functions loaded from a Python file.

A user function file is plain Python: every public top-level function is
callable from a domain by its name, case-insensitively. Arguments arrive as
plain Python values (numbers as ``float``, symbols as lower-case ``str``, lists
as Python lists, ``nil`` as ``[]``) and the return value is converted back the
same way (``None``/``False`` become ``nil``, ``True`` becomes ``1.0``). A
function used as a ``:sort-by`` comparator takes two such values and returns a
negative, zero or positive number (manual appendix B).

A user function (or a functions file as it loads) that raises anything
(any ``BaseException``: ``sys.exit``, ``GeneratorExit``, its own
``KeyboardInterrupt``), or returns something that is not a term, is an input
error located at the line of the user's file that raised (else the caller
reports it at the call's place in the domain,
:func:`htn.jshop.language.terms.at_call`). Only the stops htn's own handlers
raise (Ctrl-C, SIGTERM, ``--timeout``: :func:`~.errors.is_stop`) pass
through; under a command's stops (a table's ``guard``,
:class:`htn.process.Stops`) one that user code caught and dropped is raised
again as soon as its function returns, and the watchdog
(:mod:`htn.process.watchdog`) ends user code that does not return (the guard
names what runs).
"""

from __future__ import annotations

import math
import operator
import os
import types
from collections.abc import Callable, Container
from typing import TYPE_CHECKING, Any

from .digest import sha256_hex
from .errors import HtnError, is_stop
from .terms import NIL, Dotted, shown_term

if TYPE_CHECKING:
    # what a call term runs: its ground arguments to a term
    _Function = Callable[[tuple[Any, ...]], Any]
    _Truth = float | tuple[Any, ...]  # TRUE or NIL

TRUE = 1.0


def _num(x: Any, fn: str) -> float:
    if type(x) is not float:
        raise HtnError(f"call {fn}: expected a number, got {shown_term(x)}")
    return x


def _plus(args: tuple[Any, ...]) -> float:
    s = 0.0
    for a in args:
        s += a if type(a) is float else _num(a, "+")
    return s


def _mult(args: tuple[Any, ...]) -> float:
    s = 1.0
    for a in args:
        s *= _num(a, "*")
    return s


def _fold(op: Callable[[float, float], float], name: str) -> _Function:
    def f(args: tuple[Any, ...]) -> float:
        if len(args) == 2:  # the common case
            a, b = args
            if type(a) is float and type(b) is float:
                return op(a, b)
        res = _num(args[0], name)
        for a in args[1:]:
            res = op(res, _num(a, name))
        return res

    return f


def _div(a: float, b: float) -> float:
    if b == 0.0:
        # Java double division: x/0 is +-Infinity, 0/0 is NaN
        if a == 0.0 or a != a:
            return math.nan
        return math.copysign(math.inf, a) * math.copysign(1.0, b)
    return a / b


def _pow(a: float, b: float) -> float:
    try:
        return math.pow(a, b)
    except (OverflowError, ValueError):
        return math.nan if a < 0 else math.inf


def _chain(test: Callable[[float, float], object], name: str) -> _Function:
    def f(args: tuple[Any, ...]) -> _Truth:
        if len(args) == 2:  # the common case, without zip and slicing
            a, b = args
            if type(a) is not float or type(b) is not float:
                _num(a, name), _num(b, name)
            return TRUE if test(a, b) else NIL
        for a, b in zip(args, args[1:]):
            if not test(_num(a, name), _num(b, name)):
                return NIL
        return TRUE

    return f


def _equal(args: tuple[Any, ...]) -> _Truth:
    for a, b in zip(args, args[1:]):
        if not (a == b and type(a) is type(b)):
            return NIL
    return TRUE


def _not_equal(args: tuple[Any, ...]) -> _Truth:
    for a, b in zip(args, args[1:]):
        if a == b and type(a) is type(b):
            return NIL
    return TRUE


def _member(args: tuple[Any, ...]) -> _Truth:
    if len(args) < 2 or type(args[1]) is not tuple:
        raise HtnError("call member: the second argument must be a list")
    x = args[0]
    for y in args[1]:
        if x == y and type(x) is type(y):
            return TRUE
    return NIL


STDLIB: dict[str, _Function] = {
    "+": _plus,
    "-": _fold(operator.sub, "-"),
    "*": _mult,
    "/": _fold(_div, "/"),
    "^": _fold(_pow, "^"),
    "<": _chain(operator.lt, "<"),
    "<=": _chain(operator.le, "<="),
    ">": _chain(operator.gt, ">"),
    ">=": _chain(operator.ge, ">="),
    "=": _equal,
    "!=": _not_equal,
    "member": _member,
}

# How many arguments a standard function needs, where any number will not do:
# (min, max or None). JSHOP2 leaves these unchecked until run time.
STDLIB_ARITY: dict[str, tuple[int, int | None]] = {
    "-": (1, None),
    "/": (1, None),
    "^": (1, None),
    "member": (2, 2),
}


def arity_error(name: str, given: int) -> str | None:
    """Why ``(call name ...)`` with ``given`` arguments can never work, or None."""
    least, most = STDLIB_ARITY.get(name, (0, None))
    if given < least:
        return (
            f"call {name} needs at least {least} argument{'s' if least > 1 else ''}, given {given}"
        )
    if most is not None and given > most:
        return f"call {name} takes {most} arguments, given {given}"
    return None


# Names JSHOP2 prints for standard functions inside an unevaluated call term.
STDLIB_JAVA_NAMES = {
    "+": "StdLib.plus",
    "-": "StdLib.minus",
    "*": "StdLib.mult",
    "/": "StdLib.div",
    "^": "StdLib.power",
    "<": "StdLib.less",
    "<=": "StdLib.lessEq",
    ">": "StdLib.more",
    ">=": "StdLib.moreEq",
    "=": "StdLib.equal",
    "!=": "StdLib.notEq",
    "member": "StdLib.member",
}


def to_python(t: Any) -> Any:
    """Convert a ground term to the plain value a user function receives."""
    tt = type(t)
    if tt is tuple:
        return [to_python(x) for x in t]
    if tt is Dotted:
        return [to_python(x) for x in t.items] + [to_python(t.tail)]
    return t


def from_python(v: Any) -> Any:
    """Convert a user function's return value back to a term."""
    tv = type(v)
    if tv is float:
        return v
    if tv is int:
        return float(v)
    if v is None or v is False:
        return NIL
    if v is True:
        return TRUE
    # subclasses of the built-in types are read by the built-in types' own
    # methods: no method of the user's class runs (it might raise or loop)
    if isinstance(v, int):
        return float(int.__index__(v))
    if isinstance(v, float):
        return float.__float__(v)
    if isinstance(v, str):
        return str.lower(v)
    if isinstance(v, list):
        return tuple(from_python(x) for x in list.__iter__(v))
    if isinstance(v, tuple):
        return tuple(from_python(x) for x in tuple.__iter__(v))
    raise HtnError(f"a user function returned {_shown(v)}, which is not a term")


def _shown(v: Any, limit: int = 80) -> str:
    """A user value for a message: its repr, cut to ``limit`` characters
    (built-in values only: a user class's ``__repr__`` is not called)."""
    if type(v) in (int, float, str, bool, type(None)):
        text = repr(v) if type(v) is not str or len(v) <= 4 * limit else repr(v[: 4 * limit])
    elif type(v) in (list, tuple, dict):
        text = f"a {type(v).__name__} of {len(v)} element(s)"
    else:
        text = f"an object of class {type(v).__qualname__}"
    return _clip(text, limit)


def _clip(text: str, limit: int) -> str:
    return text if len(text) <= limit else text[: limit - 3] + "..."


class Guard:
    """How user code runs: plainly. A command's :class:`htn.process.Stops`
    is a guard too: it names the code that runs (for its watchdog) and
    raises again a stop the code caught (:meth:`dropped`)."""

    def enter(self, what: str) -> object:
        """User code (``what``: ``function spin``) starts; the token is for
        :meth:`dropped` and :meth:`leave`."""
        return None

    def leave(self, token: object) -> None:
        """It returned or raised."""

    def dropped(self, token: object) -> BaseException | None:
        """A stop raised into the user code since :meth:`enter` that it
        caught (dropped, or turned into its own): the caller raises it."""
        return None


PLAIN = Guard()


def _user_frame(exc: BaseException, files: Container[str]) -> tuple[str | None, int | None]:
    """(file, line) of the innermost frame of ``exc``'s traceback in one
    of ``files`` (the user's own code), or (None, None)."""
    place: tuple[str | None, int | None] = (None, None)
    tb = exc.__traceback__
    while tb is not None:
        name = tb.tb_frame.f_code.co_filename
        if name in files:
            place = (name, tb.tb_lineno)
        tb = tb.tb_next
    return place


def _message(exc: BaseException) -> str:
    try:
        text = BaseException.__str__(exc)
    except BaseException:  # noqa: BLE001 - a user exception whose str fails
        text = ""
    return f"{type(exc).__name__}: {_clip(text, 160)}" if text else type(exc).__name__


def user_error(what: str, exc: BaseException, files: Container[str] = ()) -> HtnError:
    """``exc`` (raised by user code) as one line at the user's file:line."""
    if isinstance(exc, SystemExit):
        text = f"{what} called sys.exit({_shown(exc.code)})"
    elif isinstance(exc, RecursionError):
        text = f"{what} recursed too deeply"
    else:
        text = f"{what} raised {_message(exc)}"
    file, line = _user_frame(exc, files)
    err = HtnError(text, file, line)
    err.in_user_code = file is not None  # at_call adds where the domain called it
    return err


def run_user_code(what: str, fn: Callable[..., Any], *args: Any, guard: Guard = PLAIN) -> Any:
    """``fn(*args)``; anything it raises but htn's own stops becomes an
    :class:`HtnError` naming ``what`` ran, at the user's line that raised
    (else the caller adds the place of the call). A stop the function
    caught and dropped is raised again when it returns (``guard``)."""
    token = guard.enter(what)
    try:
        result = fn(*args)
    except HtnError:
        raise
    except BaseException as exc:  # noqa: BLE001 - the user's code failed: report, no traceback
        if is_stop(exc):
            raise
        stop = guard.dropped(token)
        if stop is not None:
            raise stop from None  # it turned our stop into its own
        code = getattr(fn, "__code__", None)
        raise user_error(what, exc, {code.co_filename} if code else ()) from None
    finally:
        guard.leave(token)
    stop = guard.dropped(token)
    if stop is not None:
        raise stop  # it swallowed a stop: the command stops all the same
    return result


def wrap_user_function(name: str, fn: Callable[..., Any], table: FunctionTable) -> _Function:
    what = f"function {name}"

    def call(args: tuple[Any, ...]) -> Any:
        result = run_user_code(
            what,
            fn,
            *[a if type(a) is str or type(a) is float else to_python(a) for a in args],
            guard=table.guard,
        )
        try:
            return from_python(result)
        except (OverflowError, RecursionError, ValueError):  # huge, nested in itself, NaN int
            raise HtnError(
                f"function {name} returned {_shown(result)}, which is not a term"
            ) from None

    call.__name__ = name
    return call


def compare(name: str, fn: Callable[..., Any], a: Any, b: Any, guard: Guard = PLAIN) -> int:
    """A user comparator's verdict on two terms: negative, zero or positive
    (manual appendix B); anything but a number is an error."""
    r = run_user_code(f"comparator {name}", fn, to_python(a), to_python(b), guard=guard)
    n: float | None = None
    if not isinstance(r, bool) and isinstance(r, (int, float)):
        # the built-in value, without calling a subclass's methods
        n = int.__index__(r) if isinstance(r, int) else float.__float__(r)
    if n is None or n != n:
        raise HtnError(
            f"comparator {name} returned {_shown(r)}, not a number (negative, zero or positive)"
        )
    return (n > 0) - (n < 0)


class FunctionTable:
    """Maps call names (case-insensitive) to callables on term tuples."""

    def __init__(self, guard: Guard = PLAIN) -> None:
        self.guard = guard  # how user code runs (a command's stops)
        self.calls: dict[str, _Function] = dict(STDLIB)
        self.user: dict[str, Callable[..., Any]] = {}
        self.source: str | None = None
        self.sha256: str | None = None  # of the bytes of the file loaded

    def lookup(self, name: str) -> _Function | None:
        return self.calls.get(name.lower())

    def comparator(self, name: str) -> Callable[..., Any] | None:
        return self.user.get(name.lower())

    def load_file(self, path: str, check: Callable[[str], None] | None = None) -> None:
        """Load every public top-level function of a Python file (whatever
        its name ends with: it is read as Python source). The file is read
        once: ``check(sha256)`` sees the SHA-256 of its bytes before they
        run (and may refuse them), and the same bytes are compiled."""
        if not os.path.isfile(path):
            raise HtnError("functions file not found", path)
        try:
            with open(path, "rb") as fh:
                data = fh.read()
        except OSError as exc:
            raise HtnError(f"cannot read: {exc.strerror}", path) from None
        digest = sha256_hex(data)
        if check is not None:
            check(digest)
        module = types.ModuleType("_htn_user_functions")
        module.__file__ = path
        guard = self.guard
        token = guard.enter(f"the functions file {path}")
        try:
            exec(compile(data, path, "exec", dont_inherit=True), module.__dict__)
        except SyntaxError as exc:
            raise HtnError(
                f"syntax error: {_clip(str(exc.msg), 160)}", path, exc.lineno, exc.offset
            ) from None
        except HtnError:
            raise
        except BaseException as exc:  # noqa: BLE001 - the file failed to load: one line
            if is_stop(exc):
                raise
            stop = guard.dropped(token)
            if stop is not None:
                raise stop from None
            err = user_error("loading failed: it", exc, {path})
            if err.file is None:
                err.file = path
            raise err from None
        finally:
            guard.leave(token)
        stop = guard.dropped(token)
        if stop is not None:
            raise stop
        self.source, self.sha256 = path, digest
        for name, fn in vars(module).items():
            if name.startswith("_") or not isinstance(fn, types.FunctionType):
                continue
            if fn.__module__ != module.__name__:
                continue  # imported helpers are not the file's own functions
            self.user[name.lower()] = fn
            self.calls[name.lower()] = wrap_user_function(name, fn, self)
