"""The list structure of a JSHOP2 or HDDL text, and what its layout says of it.

Both languages are lists in parentheses, with ``;`` comments and no strings
(JSHOP2 manual 3.14). When a file does not parse, the parser only knows where
the structure broke, which is often lines after the slip: a missing ``)``
shows up at the next ``(:operator``, an extra one at whatever follows. The
layout of a hand-written file knows more: a line that starts at or left of
the line where a list opened is not inside that list. :func:`layout_suspects`
reads the places where parentheses and layout disagree; the reader then tries
each fix on the text (:mod:`htn.jshop.readers.lark_errors`), and names a
parenthesis only when the fixed text parses.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

_TOKEN = re.compile(r"[()]|;[^\n\r]*|[^\s();]+")


@dataclass
class List_:
    """A list opened at ``start`` (its ``(``): where, on what line, and what
    it holds so far (``items``: '(' for a list, else the word)."""

    start: int
    line: int
    col: int
    indent: int  # column of the first token of its line
    items: list = field(default_factory=list)

    @property
    def head(self) -> str:
        """Its first word, lower-case ('' when it starts with a list)."""
        return self.items[0].lower() if self.items and self.items[0] != "(" else ""


@dataclass
class Suspect:
    """A parenthesis the layout disagrees with. ``unclosed``: the list
    ``opened`` is never closed, the fix inserts a ``)`` at offset ``at``;
    ``extra``: the ``)`` at ``at`` closes ``opened`` too early, the fix
    removes it. ``line`` is the first line whose layout shows it."""

    kind: str  # "unclosed" | "extra"
    at: int  # offset to insert at, or of the ')' to remove
    opened: List_
    line: int

    def fixed(self, text: str) -> str:
        if self.kind == "unclosed":
            return text[: self.at] + ")" + text[self.at :]
        return text[: self.at] + text[self.at + 1 :]


def scan(text: str, upto: int | None = None):
    """Walk the tokens before offset ``upto``; yields ``(token, offset, line,
    col, first, stack)`` for each '(' / ')' / word (comments skipped):
    ``first`` when it is the first token of its line, ``stack`` the lists
    open *before* it (one list object, updated as the walk goes on)."""
    stack: list[List_] = []
    line, bol = 1, 0
    first_col = None  # column of the line's first token
    end = len(text) if upto is None else upto
    for m in _TOKEN.finditer(text, 0, end):
        tok, at = m.group(), m.start()
        nl = text.count("\n", bol, at)
        if nl:
            line += nl
            bol = text.rfind("\n", 0, at) + 1
            first_col = None
        if tok.startswith(";"):
            continue
        col = at - bol + 1
        if first_col is None:
            first_col = col
        yield tok, at, line, col, first_col == col, stack
        if tok == "(":
            if stack:
                stack[-1].items.append("(")
            stack.append(List_(at, line, col, first_col))
        elif tok == ")":
            if stack:
                stack.pop()
        elif stack:
            stack[-1].items.append(tok)


def open_lists(text: str, upto: int) -> list[List_]:
    """The lists still open at offset ``upto``, outermost first."""
    stack: list[List_] = []
    for *_, stack in scan(text, upto):  # noqa: B007 (the last one is the answer)
        pass  # the same list, up to date once the scan ends
    return list(stack)


def layout_suspects(text: str, upto: int | None = None, limit: int = 4) -> list[Suspect]:
    """Parentheses the layout disagrees with, before offset ``upto``, in
    text order (at most ``limit``):

    - unclosed: a line starts (with anything but ``)``) at or left of the
      indentation of the line where a list still open was opened on an
      earlier line; the innermost such list is the suspect, and the fix is
      a ``)`` after the last token before that line;
    - extra: a ``)`` closes a list opened on an earlier line, and the next
      line starts right of the indentation of the line where that list
      opened, as lines inside it do; the fix is to remove that ``)``.
    """
    found: list[Suspect] = []
    prev_end = 0  # end of the previous token
    closed: tuple | None = None  # (list closed last, offset of its ')'), this line
    for tok, at, line, col, first, stack in scan(text, upto):
        if first and tok != ")":
            late = [s for s in stack if s.line < line and s.indent >= col]
            if late:
                found.append(Suspect("unclosed", prev_end, late[-1], line))
            elif (
                closed is not None
                and closed[0].indent < col
                and closed[0].line < line
                and (not stack or stack[-1].indent < col)
            ):
                found.append(Suspect("extra", closed[1], closed[0], line))
            closed = None
            if len(found) >= limit:
                break
        if tok == ")" and stack:
            if stack[-1].line < line:
                closed = (stack[-1], at)
        prev_end = at + len(tok)
    return found


def first_unmatched_close(text: str, upto: int | None = None) -> int | None:
    """Offset of the first ``)`` that closes nothing, if any."""
    for tok, at, *_, stack in scan(text, upto):
        if tok == ")" and not stack:
            return at
    return None
