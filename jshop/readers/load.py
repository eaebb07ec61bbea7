"""Load domains and problems: the reader is chosen by content, JSHOP2 or HDDL.

HDDL text (``(define (domain ...`` or ``(define (problem ...``) is read by
:mod:`htn.jshop.readers.hddl_fast` (or, where that reader is not sure of the
text, by the lark grammar of :mod:`htn.jshop.readers.hddl`, which locates the
error) and turned into the same syntax objects as JSHOP2 text
(:mod:`htn.jshop.readers.hddl_domain`); JSHOP2 text the same way, by
:mod:`htn.jshop.readers.jshop2_fast` or else :mod:`htn.jshop.readers.jshop2`.
Each reader is imported only for its input: lark is not loaded for
well-formed input.
"""

from __future__ import annotations

import os
import re

from htn.jshop.language import syntax as S
from htn.jshop.language.digest import sha256_hex
from htn.jshop.language.errors import HtnError
from htn.jshop.language.functions import FunctionTable

from .checks import check_domain_name, check_inputs
from .source import check_nesting, check_not_empty, decode_source, read_bytes

_HDDL_HEAD = re.compile(r"\A(?:\s|;[^\n]*\n)*\(\s*define\s*\(\s*(domain|problem)\b", re.I)


def is_hddl(text: str) -> bool:
    """True if the text starts like an HDDL (PDDL) file: ``(define (domain``
    or ``(define (problem``, after comments."""
    return _HDDL_HEAD.match(text) is not None


def parse_text(
    text: str,
    file: str = "<string>",
    functions: FunctionTable | None = None,
    expect: str | None = None,
):
    """Parse a domain or problem (``expect``, if known) from text, JSHOP2 or
    HDDL; raise :class:`HtnError` on bad input."""
    check_not_empty(text, file, expect)
    check_nesting(text, file)
    if is_hddl(text):
        from . import hddl_domain, hddl_fast

        try:
            model = hddl_fast.parse_model(text, file)
        except hddl_fast.Fallback:  # not plainly well-formed: lark's reader says where
            from . import hddl

            model = hddl.parse_model(text, file)
        return hddl_domain.from_model(model)
    from . import jshop2_fast

    try:
        return jshop2_fast.parse_jshop2(text, file, functions)
    except jshop2_fast.Fallback:  # not plainly well-formed: lark's reader says where
        from .jshop2 import parse_jshop2

        return parse_jshop2(text, file, functions or FunctionTable())


def parse_file(path: str, functions: FunctionTable | None = None, expect: str | None = None):
    if not os.path.exists(path):
        raise HtnError("no such file", path)
    if os.path.isdir(path):
        raise HtnError("is a directory, not a JSHOP2 file", path)
    # the file is read once: its text is parsed, and the SHA-256 of the same
    # bytes is what a log's header records of it
    data = read_bytes(path)
    parsed = parse_text(decode_source(data, path), path, functions, expect)
    parsed.sha256 = sha256_hex(data)
    return parsed


def load_domain(path: str, functions: FunctionTable | None = None) -> S.Domain:
    d = parse_file(path, functions, "domain")
    if not isinstance(d, S.Domain):
        wanted = "(define (domain ...))" if d.language == "hddl" else "(defdomain ...)"
        raise HtnError.at(d.pos, f"expected a {wanted} here, found a problem")
    return d


def load_problem(path: str, functions: FunctionTable | None = None) -> S.Problem:
    p = parse_file(path, functions, "problem")
    if not isinstance(p, S.Problem):
        wanted = "(define (problem ...))" if p.language == "hddl" else "(defproblem ...)"
        raise HtnError.at(p.pos, f"expected a {wanted} here, found a domain")
    return p


def load_inputs(
    domain_path: str, problem_path: str, functions: FunctionTable | None = None
) -> tuple[S.Domain, S.Problem]:
    """Load a domain and a problem for it, paired (:func:`paired`) and
    checked together (:func:`htn.jshop.readers.checks.check_inputs`, the
    check every command runs; its warnings are not returned:
    :mod:`htn.api.inputs` has them)."""
    dom, prob = paired(load_domain(domain_path, functions), load_problem(problem_path, functions))
    check_inputs(dom, prob)
    return dom, prob


def paired(dom: S.Domain, prob: S.Problem) -> tuple[S.Domain, S.Problem]:
    """A domain and a problem checked to belong together, and the domain
    to plan that problem with: for HDDL, the problem's tasks that are
    actions become operators, and a problem whose initial task network is
    not totally ordered gets the domain without pulled-up conditions
    (:func:`~htn.jshop.readers.hddl_domain.for_problem`), and an initial task
    network with parameters its root method, in that domain's terms
    (``ProblemInstance.root``)."""
    check_domain_name(dom, prob)
    if dom.hddl is not None:
        from .hddl_domain import (
            attach_roots,
            check_problem_symbols,
            for_problem,
            resolve_problem_tasks,
        )

        check_problem_symbols(dom, prob)
        resolve_problem_tasks(dom, prob)
        dom = for_problem(dom, prob)
        attach_roots(dom, prob)
    return dom, prob


__all__ = [
    "is_hddl",
    "parse_text",
    "parse_file",
    "load_domain",
    "load_problem",
    "load_inputs",
    "check_domain_name",
]
