"""Limits of the search that the command line shows as defaults, and the
memory guard that stops a search before it exhausts the machine's memory.

Kept apart from :mod:`htn.jshop.search.planner` so that ``htn --help`` can show them
without loading the planner.

Two bounds stop a search that would never end (JSHOP2 ends such a search with
a ``StackOverflowError`` or an ``OutOfMemoryError``):

* the *reduction depth*: the number of nested method reductions since the last
  operator applied on the current path (``--max-depth``). A method that
  decomposes into itself before any step, ``(:method (loop) () ((loop) (!a)))``,
  deepens it by one per reduction and stops at the bound (about 2.4 kB per
  reduction: 250,000 stay well under 1 GB). A plan, however long, does not:
  every step starts the count again, so Towers with 20 rings (1,048,575 moves,
  three frames each) is not cut short, as it was when every frame counted;
* the *memory budget* (``--max-memory``): a search whose every step is a real
  operator but never ends, ``((!a) (loop))``, or a plan too long for the
  machine, stops cleanly when the process's memory reaches the budget. By
  default the budget is 80% of what the process may use: its address-space
  limit (``ulimit -v``) if one is set, and the memory available when the
  search started.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .network import Task

DEFAULT_MAX_DEPTH = 250_000

_PAGE = 4096


def _meminfo_available() -> int | None:
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    return None


def process_memory() -> tuple[int, int] | None:
    """``(address space, resident set)`` of this process in bytes, or None
    where ``/proc`` is not there."""
    try:
        with open("/proc/self/statm") as f:
            size, resident = f.read().split()[:2]
        return int(size) * _PAGE, int(resident) * _PAGE
    except (OSError, ValueError):
        return None


class MemoryGuard:
    """Says when a search has used its memory budget (see the module docstring).

    ``max_bytes`` bounds the resident memory the process may reach (None: 80%
    of the memory available now, plus what it holds already); the address
    space is kept under 80% of ``ulimit -v`` if one is set."""

    def __init__(self, max_bytes: int | None = None):
        import resource

        now = process_memory()
        self.enabled = now is not None
        self.max_space = None
        soft = resource.getrlimit(resource.RLIMIT_AS)[0]
        if soft != resource.RLIM_INFINITY:
            self.max_space = int(soft * 0.8)
        if max_bytes is None and now is not None:
            avail = _meminfo_available()
            if avail is not None:
                max_bytes = now[1] + int(avail * 0.8)
        self.max_resident = max_bytes
        self.limit_bytes = min(x for x in (self.max_space, max_bytes, 1 << 62) if x is not None)

    def exceeded(self) -> bool:
        if not self.enabled:
            return False
        space, resident = process_memory() or (0, 0)
        return (self.max_space is not None and space > self.max_space) or (
            self.max_resident is not None and resident > self.max_resident
        )


class SearchBound:
    """A bound that stopped the search, and the task being reduced deepest."""

    __slots__ = ("limit", "task")

    def __init__(self, limit: int, task: Task | None):
        self.limit = limit
        self.task = task

    def __str__(self) -> str:
        if self.task is None:
            return self.message(None)
        pos = getattr(self.task.src, "pos", None)
        return (f"{pos}: " if pos else "") + self.message(self.task)

    def message(self, task) -> str:
        raise NotImplementedError


class DepthLimit(SearchBound):
    """The search stopped at ``max_depth`` nested reductions without a step."""

    __slots__ = ()

    def message(self, task) -> str:
        what = (
            f"task {task} recurses past the search depth limit"
            if task is not None
            else "the search reached its depth limit"
        )
        return (
            f"{what} ({self.limit:,} nested reductions without a step); "
            "search stopped (raise it with --max-depth N)"
        )


class MemoryLimit(SearchBound):
    """Why the search stopped at its memory budget: the plan on the current
    path needs more memory than the budget, or the search never ends."""

    __slots__ = ()

    def message(self, task) -> str:
        at = f" at task {task}" if task is not None else ""
        return (
            f"the search used its memory budget ({self.limit >> 20:,} MB){at}; "
            "search stopped (raise it with --max-memory MB)"
        )
