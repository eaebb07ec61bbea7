"""The inputs of the use cases: each takes a path or an object already loaded.

A domain is a path (``str`` or ``os.PathLike``) or a
:class:`~htn.jshop.language.syntax.Domain`; a problem a path or a
:class:`~htn.jshop.language.syntax.Problem`; user functions (for ``(call
...)`` and ``:sort-by``) a path to a Python file, a
:class:`~htn.jshop.language.functions.FunctionTable`, or None. The JSHOP2
reader resolves calls while it reads, so a domain or problem passed as an
object must have been read with the same functions that are passed here.
Whatever is given as a path is read once, here, and every pair of a domain
and a problem gets the one static check
(:func:`htn.jshop.readers.checks.check_inputs`), so each use case accepts or
refuses the same input the same way, with the same located message.
"""

from __future__ import annotations

import os
import re
from typing import TypeGuard, cast

from htn.installation import EXAMPLES_DIR
from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError
from htn.jshop.language.functions import FunctionTable, Guard
from htn.jshop.language.record import Record
from htn.jshop.readers.checks import check_inputs
from htn.jshop.readers.load import load_domain, load_problem, paired

# what the use cases take: a path, or the object read from one
StrPath = str | os.PathLike[str]
DomainInput = StrPath | S.Domain
ProblemInput = StrPath | S.Problem
FunctionsInput = StrPath | FunctionTable | None


def is_path(x: object) -> TypeGuard[StrPath]:
    return isinstance(x, (str, os.PathLike))


def path_of(x: object) -> str | None:
    """The file ``x`` is, or was read from (None for one made in memory)."""
    if x is None:
        return None
    if is_path(x):
        return os.fspath(x)
    file: str | None = getattr(x, "file", None)
    return file or None


def function_table(functions: FunctionsInput, stops: Guard | None = None) -> FunctionTable:
    """A function table: ``functions`` itself, the functions of a Python file,
    or an empty table for None. ``stops``: the command's
    :class:`htn.process.Stops`, under which the user code runs (a table
    given runs under them from now on)."""
    if isinstance(functions, FunctionTable):
        if stops is not None:
            functions.guard = stops
        return functions
    table = FunctionTable(stops) if stops is not None else FunctionTable()
    if functions is not None:
        table.load_file(os.fspath(functions))
    return table


class Inputs(Record):
    """A domain and a problem for it, read and checked; ``warnings`` are the
    check's located warnings (``file:line:col: warning: ...``)."""

    __slots__ = ("domain", "problem", "warnings")

    def __init__(
        self, domain: S.Domain, problem: S.Problem, warnings: list[str] | None = None
    ) -> None:
        self.domain, self.problem = domain, problem
        self.warnings: list[str] = [] if warnings is None else warnings


def domain_and_problem(
    domain: DomainInput | None, problem: ProblemInput | None, table: FunctionTable
) -> tuple[S.Domain, S.Problem]:
    """The domain and the problem, read if given as paths and checked (see
    :func:`read_inputs`)."""
    inputs = read_inputs(domain, problem, table)
    return inputs.domain, inputs.problem


def read_inputs(
    domain: DomainInput | None, problem: ProblemInput | None, table: FunctionTable
) -> Inputs:
    """The domain and the problem, read if given as paths, and checked: they
    belong together (a problem names its domain: manual 3.12) and pass the
    static check every command runs (an :class:`HtnError` at
    ``file:line:col`` if not)."""
    if domain is None or problem is None:
        raise HtnError("give a domain and a problem")
    dom = load_domain(os.fspath(domain), table) if is_path(domain) else domain
    prob = load_problem(os.fspath(problem), table) if is_path(problem) else problem
    if not isinstance(dom, S.Domain):
        raise HtnError(f"expected a domain (a path or a Domain), got {type(dom).__name__}")
    if not isinstance(prob, S.Problem):
        raise HtnError(f"expected a problem (a path or a Problem), got {type(prob).__name__}")
    # paired first: for HDDL it makes the problem's action tasks operators,
    # which the check then finds
    dom, prob = paired(dom, prob)
    return Inputs(dom, prob, [str(w) for w in check_inputs(dom, prob)])


def domain_for(problem: ProblemInput) -> str:
    """The domain file of a problem (a path or a Problem read from one), by
    the name the problem gives its domain: ``NAME.jshop`` (``NAME.hddl`` or
    ``domain.hddl`` for an HDDL problem), or else a file of the language's
    extension that defines a domain of that name (``(defdomain NAME``,
    ``(define (domain NAME)``), beside the problem, in ``../domains/``
    beside it, in ``domains/`` here, or the bundled one. None found: an
    input error that names every place looked in."""
    if is_path(problem):
        problem = load_problem(os.fspath(problem))
    problem = cast(S.Problem, problem)  # read if it was a path
    name = problem.domain_name
    files = [f"{name}.hddl", "domain.hddl"] if problem.language == "hddl" else [f"{name}.jshop"]
    # the places as the user wrote the problem's path (a message shows the
    # path they gave), each looked in once
    here = os.path.dirname(problem.file or "")
    places = [
        here,
        os.path.join(here, "..", "domains"),
        "domains",
        os.path.join(EXAMPLES_DIR, "domains"),
    ]
    looked: list[str] = []
    for base in places:
        base = os.path.normpath(base)
        if any(os.path.abspath(base) == os.path.abspath(b) for b in looked):
            continue
        looked.append(base)
        for file in files:
            path = os.path.normpath(os.path.join(base, file))
            if os.path.isfile(path):
                return path
        found = _defining(base, name, problem.language)
        if found is not None:
            return found
    shown = [os.path.join(p, "") for p in looked]
    raise HtnError(
        f"cannot find the domain file {' or '.join(files)}: looked in "
        f"{', '.join(shown[:-1])} and {shown[-1]}; give it with --domain",
        problem.file,
    )


HEAD = 65536  # bytes of a file read to see which domain it defines


def _defining(folder: str, name: str, language: str) -> str | None:
    """The first file (by name) in ``folder`` with the language's extension
    whose text defines the domain ``name``, or None."""
    ext = ".hddl" if language == "hddl" else ".jshop"
    pattern = (
        rf"\(\s*define\s*\(\s*domain\s+{re.escape(name)}\s*\)"
        if language == "hddl"
        else rf"\(\s*defdomain\s+{re.escape(name)}[\s(]"
    )
    try:
        entries = sorted(os.listdir(folder))
    except OSError:
        return None
    for entry in entries:
        path = os.path.normpath(os.path.join(folder, entry))
        if not entry.lower().endswith(ext) or not os.path.isfile(path):
            continue
        try:
            with open(path, "rb") as fh:
                head = fh.read(HEAD).decode("utf-8", "replace")
        except OSError:
            continue
        head = re.sub(r";[^\n]*", "", head)  # comments
        if re.search(pattern, head, re.IGNORECASE if language == "hddl" else 0):
            return path
    return None
