"""Generated code that tracebacks and debuggers can show.

The planner compiles parts of a domain into Python source at run time (JSHOP2
compiles a domain into Java, manual section 4): argument binders, head
unifiers, conjunctions per binding mode, method bodies. :func:`define` is the
one place that source is compiled. Each piece is compiled under a file name
that says what it compiles, ``<htn: precondition of !grasp, domestic.jshop:41>``,
and its source is registered with :mod:`linecache`, so a traceback through it
shows the generated lines and ``pdb`` can list and step through them.

``HTN_DUMP_COMPILED=DIR`` (read when a piece is compiled, so a program that
sets it later is heard) also writes every piece to a file in ``DIR`` named
after what it compiles.

Compiling costs far more than running a piece once (Python compiles about a
microsecond per character of source), and a small search runs most pieces a
few times only: see :mod:`~htn.jshop.logic.warming` for when a piece is
compiled.
"""

from __future__ import annotations

import linecache
import os
import re

from .caches import on_clear

_SOURCES: dict = {}  # file name -> source compiled under it


def where(pos) -> str:
    """``file:line`` of a syntax object's ``pos`` (the file's base name), or ''."""
    if pos is None:
        return ""
    return f"{os.path.basename(pos.file)}:{pos.line}"


def described(what: str, pos=None) -> str:
    """``what, file:line`` (or just ``what`` without a position)."""
    place = where(pos)
    return f"{what}, {place}" if place else what


def define(src: str, what: str, ns: dict) -> dict:
    """Compile and run ``src`` (the definitions of generated functions) in
    ``ns`` under the file name ``<htn: what>``, registered with linecache;
    returns ``ns``. The same ``what`` with another source gets ``#2``, ``#3``..."""
    name = f"<htn: {what}>"
    known = _SOURCES.get(name)
    n = 1
    while known is not None and known != src:
        n += 1
        name = f"<htn: {what} #{n}>"
        known = _SOURCES.get(name)
    if known is None:
        _SOURCES[name] = src
        # mtime None: linecache.checkcache keeps the entry (there is no file)
        linecache.cache[name] = (len(src), None, src.splitlines(True), name)
        dump_dir = os.environ.get("HTN_DUMP_COMPILED")
        if dump_dir:
            _dump(dump_dir, name, src)
    exec(compile(src, name, "exec"), ns)
    return ns


def _dump(dump_dir: str, name: str, src: str) -> None:
    os.makedirs(dump_dir, exist_ok=True)
    stem = re.sub(r"[^A-Za-z0-9._-]+", "_", name[6:-1]).strip("_")[:150] or "code"
    # the lines as a traceback numbers them; what they are at the end
    with open(os.path.join(dump_dir, stem + ".py"), "w", encoding="utf-8") as f:
        f.write(f"{src}\n# {name}\n")


def _forget() -> None:
    for name in _SOURCES:
        linecache.cache.pop(name, None)
    _SOURCES.clear()


on_clear(_forget)
