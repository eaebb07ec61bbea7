"""The inputs of the use cases: each takes a path or an object already loaded.

A domain is a path (``str`` or ``os.PathLike``) or a
:class:`~htn.jshop.language.syntax.Domain`; a problem a path or a
:class:`~htn.jshop.language.syntax.Problem`; user functions (for ``(call
...)`` and ``:sort-by``) a path to a Python file, a
:class:`~htn.jshop.language.functions.FunctionTable`, or None. The JSHOP2
reader resolves calls while it reads, so a domain or problem passed as an
object must have been read with the same functions that are passed here.
Whatever is given as a path is read once, here.
"""
from __future__ import annotations

import os
from typing import Optional

from htn.installation import EXAMPLES
from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError
from htn.jshop.language.functions import FunctionTable
from htn.jshop.readers.load import load_domain, load_problem, paired

def is_path(x) -> bool:
    return isinstance(x, (str, os.PathLike))


def path_of(x) -> Optional[str]:
    """The file ``x`` is, or was read from (None for one made in memory)."""
    if x is None:
        return None
    if is_path(x):
        return os.fspath(x)
    return getattr(x, "file", None) or None


def function_table(functions) -> FunctionTable:
    """A function table: ``functions`` itself, the functions of a Python file,
    or an empty table for None."""
    if isinstance(functions, FunctionTable):
        return functions
    table = FunctionTable()
    if functions is not None:
        table.load_file(os.fspath(functions))
    return table


def domain_and_problem(domain, problem, table: FunctionTable) -> tuple[S.Domain, S.Problem]:
    """The domain and the problem, read if given as paths, and checked to
    belong together (a problem names its domain: manual 3.12); for HDDL the
    domain as that problem needs it (:func:`~htn.jshop.readers.load.paired`)."""
    if domain is None or problem is None:
        raise HtnError("give a domain and a problem")
    dom = load_domain(os.fspath(domain), table) if is_path(domain) else domain
    prob = load_problem(os.fspath(problem), table) if is_path(problem) else problem
    if not isinstance(dom, S.Domain):
        raise HtnError(f"expected a domain (a path or a Domain), got {type(dom).__name__}")
    if not isinstance(prob, S.Problem):
        raise HtnError(f"expected a problem (a path or a Problem), got {type(prob).__name__}")
    return paired(dom, prob)


def domain_for(problem) -> str:
    """The domain file of a problem (a path or a Problem read from one):
    ``../domains/NAME.jshop`` beside it, ``domains/NAME.jshop`` here, or the
    bundled one of that name (NAME is the domain the problem names)."""
    if is_path(problem):
        problem = load_problem(os.fspath(problem))
    name = problem.domain_name
    problem = problem.file
    for base in (os.path.join(os.path.dirname(os.path.abspath(problem)), "..", "domains"),
                 "domains", str(EXAMPLES / "domains")):
        path = os.path.normpath(os.path.join(base, f"{name}.jshop"))
        if os.path.isfile(path):
            return path
    raise HtnError(f"cannot find the domain file {name}.jshop; give it with --domain", problem)
