"""User-facing errors: each names the place in the input it is about; and
the stops (interrupts, the deadline) htn raises into the program, told apart
from what user code raises."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from typing import Protocol

    class Place(Protocol):
        """A place in the input: a :class:`htn.jshop.language.syntax.Pos`
        (not imported: the syntax imports this module)."""

        @property
        def file(self) -> str: ...
        @property
        def line(self) -> int: ...
        @property
        def col(self) -> int: ...


class HtnError(Exception):
    """An error in the user's input, printed as ``file:line:col: message``.

    The command line catches these once, prints them on one line (plus the
    offending source line when it is known) and exits with code 2.
    """

    # set on the instance only, for an error raised in a user function
    # (functions.user_error; terms.at_call reads it with getattr)
    in_user_code: bool

    def __init__(
        self,
        message: str,
        file: str | None = None,
        line: int | None = None,
        col: int | None = None,
    ) -> None:
        super().__init__(message)
        self.message = message
        self.file = file
        self.line = line
        self.col = col

    @classmethod
    def at(cls, pos: Place | None, message: str) -> HtnError:
        if pos is None:
            return cls(message)
        return cls(message, pos.file, pos.line, pos.col)

    def location(self) -> str:
        parts = [p for p in (self.file, self.line, self.col) if p is not None]
        return ":".join(str(p) for p in parts)

    def __str__(self) -> str:
        loc = self.location()
        return f"{loc}: {self.message}" if loc else self.message

    def source_line(self) -> str | None:
        """The offending line of the input file with a caret, if readable;
        a line longer than :data:`SHOWN` characters is shown around the column."""
        if not self.file or not self.line:
            return None
        try:
            with open(self.file, encoding="utf-8-sig", errors="replace") as fh:
                for i, text in enumerate(fh, 1):
                    if i == self.line:
                        text = text.rstrip("\n\r").expandtabs(1)
                        return _with_caret(text, max((self.col or 1) - 1, 0))
        except (OSError, ValueError):
            return None
        return None


SHOWN = 200  # characters of a source line echoed under an error


def _with_caret(text: str, at: int) -> str:
    """``text`` and a caret under column ``at`` (0-based), cut to about
    :data:`SHOWN` characters around it with ``...`` where text is left out."""
    if len(text) > SHOWN:
        start = min(max(at - SHOWN // 2, 0), len(text) - SHOWN)
        end = start + SHOWN
        head = "..." if start > 0 else ""
        tail = "..." if end < len(text) else ""
        text, at = head + text[start:end] + tail, at - start + len(head)
    return f"  {text}\n  {' ' * at}^"


class PlanningError(HtnError):
    """Raised during search, e.g. an operator cost that is not a number."""


class WriteError(HtnError):
    """An output could not be written (a full disk, a failing device, a
    read-only file system); ``file`` is its path. What was there before is
    kept (a file replaced whole) or ends on its last whole line (a log)."""


STOP_MARK = "htn_stop"


def mark_stop(exc: BaseException) -> BaseException:
    """``exc``, marked as a stop that htn itself raises (Ctrl-C, SIGTERM,
    ``--timeout``: :class:`htn.process.Stops`, see :func:`is_stop`); the
    caller raises it."""
    setattr(exc, STOP_MARK, True)
    return exc


def is_stop(exc: BaseException) -> bool:
    """Was ``exc`` raised by htn's own handlers (an interrupt or the
    deadline), not by user code (which may raise ``KeyboardInterrupt`` too)?"""
    return getattr(exc, STOP_MARK, False) is True
