"""The text of an input file, and the limit on how deeply it may nest.

Files are UTF-8, with or without a byte-order mark. Parentheses may nest at
most :data:`MAX_NESTING` deep: the manual sets no limit, but the term
functions recurse over list terms, and no domain nests anywhere near that deep.
"""

from __future__ import annotations

import re

from htn.jshop.language.errors import HtnError

MAX_NESTING = 1000  # levels of parentheses


def read_source(path: str) -> str:
    """The text of a UTF-8 file (a byte-order mark is dropped); bytes that are
    not UTF-8 are an error at their line and column."""
    return decode_source(read_bytes(path), path)


def read_bytes(path: str) -> bytes:
    """The bytes of an input file; a file that cannot be read is an error."""
    try:
        with open(path, "rb") as fh:
            return fh.read()
    except OSError as exc:
        raise HtnError(f"cannot read: {exc.strerror}", path) from exc


def decode_source(data: bytes, path: str) -> str:
    """The text of a file's bytes, as :func:`read_source` reads it (for a
    reader that also needs the bytes, e.g. to take their SHA-256)."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        start = exc.start
        line = data.count(b"\n", 0, start) + 1
        bol = data.rfind(b"\n", 0, start) + 1
        col = len(data[bol:start].decode("utf-8-sig" if bol == 0 else "utf-8", "replace")) + 1
        raise HtnError(
            f"not UTF-8 text: byte 0x{data[start]:02x} ({exc.reason})", path, line, col
        ) from None


_PAREN_OR_COMMENT = re.compile(r"[()]|;[^\n\r]*")


def check_nesting(text: str, file: str) -> None:
    """Refuse parentheses nested deeper than :data:`MAX_NESTING`, at the first
    one too deep (comments are skipped, as the grammar skips them)."""
    if text.count("(") <= MAX_NESTING:
        return
    depth = 0
    for m in _PAREN_OR_COMMENT.finditer(text):
        c = m.group()
        if c == "(":
            depth += 1
            if depth > MAX_NESTING:
                line, col = position(text, m.start())
                raise HtnError(f"parentheses nested more than {MAX_NESTING} deep", file, line, col)
        elif c == ")":
            depth -= 1


_EMPTY = re.compile(r"(?:\s|;[^\n\r]*)*")

EXPECTED_FORM = {  # (language, what) -> the form an empty file should hold
    ("jshop2", "domain"): "(defdomain NAME (...))",
    ("jshop2", "problem"): "(defproblem NAME DOMAIN (ATOM ...) (TASK ...))",
    ("jshop2", None): "(defdomain NAME (...)) or (defproblem NAME DOMAIN (...) (...))",
    ("hddl", "domain"): "(define (domain NAME) ...)",
    ("hddl", "problem"): "(define (problem NAME) (:domain DOMAIN) ...)",
    ("hddl", None): "(define (domain NAME) ...) or (define (problem NAME) ...)",
}


def check_not_empty(text: str, file: str, expect: str | None = None) -> None:
    """Refuse a file with nothing but blanks and comments, saying what it
    should hold: a domain or a problem (``expect``), JSHOP2 or HDDL (by the
    file name's ending ``.hddl``)."""
    if _EMPTY.fullmatch(text) is None:
        return
    language = "hddl" if file.lower().endswith(".hddl") else "jshop2"
    what = "empty file" if not text.strip() else "nothing but comments in this file"
    raise HtnError(f"{what}, expected {EXPECTED_FORM[language, expect]}", file, 1, 1)


def position(text: str, offset: int) -> tuple[int, int]:
    """1-based line and column of a character offset."""
    line = text.count("\n", 0, offset) + 1
    return line, offset - (text.rfind("\n", 0, offset) + 1) + 1
