"""The option types of every command's times and counts.

Two types, one message each, the same on every command: :class:`Timeout`
for seconds (``--timeout``) and :class:`Count` for whole numbers (``-n``,
``--repeat``, ``--runs``, ``--workers``, ``--plan-index``, ``--max-depth``,
``--max-memory``, ``--seed``, ports). NaN, infinities (but ``--timeout inf``),
negatives, zero where it means nothing, fractions and values past what the
clock or the machine can hold are usage errors (exit 2), never a traceback
deep in the command.
"""

from __future__ import annotations

import math
import os

import click

from htn.process import Stops

TIMEOUT_HELP = (
    "Wall-clock limit of the whole command in seconds, loading included "
    "(user functions too); 'inf' for none."
)


def current_stops() -> Stops:
    """The running command's stops: :func:`htn.cli.main.main` gives them
    to click as the context's object (a command invoked without it gets
    its own)."""
    return click.get_current_context().ensure_object(Stops)


MAX_COUNT = 2**63 - 1  # what a machine word holds: C code (PyBullet, numpy) takes no more
MAX_RUNS = 10**6  # --repeat, --runs: a million runs is days of work already
MAX_WORKERS = 256  # processes on one machine


class Timeout(click.ParamType):
    """``--timeout SECONDS``: a positive number of seconds, or ``inf`` (no
    limit, None). Zero, a negative number, NaN or anything unparsable is a
    usage error (exit 2). A limit past what the interval timer holds (over
    three years) is no limit, as ``inf``."""

    name = "seconds"

    def convert(self, value, param, ctx):
        if value is None or isinstance(value, float) and value > 0:
            return None if value is None or math.isinf(value) else value
        text = str(value).strip()
        try:
            seconds = float(text)
        except ValueError:
            self.fail(f"{text[:40]!r} is not a number of seconds (e.g. 10, 0.5 or inf)", param, ctx)
        if math.isnan(seconds) or seconds <= 0:
            self.fail(
                f"{text[:40]!r}: give a positive number of seconds (or inf for no limit)",
                param,
                ctx,
            )
        return None if math.isinf(seconds) else seconds


class Count(click.ParamType):
    """A whole number from ``low`` to ``high``, written in decimal digits
    (``1e3``, ``0x10``, ``1_000`` and fractions are not whole numbers here)."""

    name = "integer"

    def __init__(self, low: int = 1, high: int = MAX_COUNT):
        self.low, self.high = low, high

    def convert(self, value, param, ctx):
        if (
            isinstance(value, int)
            and not isinstance(value, bool)
            and self.low <= value <= self.high
        ):
            return value
        text = str(value).strip()
        try:
            n = int(text.replace("_", "x"), 10)  # int() takes 1_000; a user means no such thing
        except ValueError:
            self.fail(
                f"{text[:40]!r} is not a whole number; give one from {self.low} to {self.high}",
                param,
                ctx,
            )
        if not self.low <= n <= self.high:
            self.fail(
                f"{text[:40]!r}: give a whole number from {self.low} to {self.high}", param, ctx
            )
        return n

    def __repr__(self) -> str:
        return f"Count({self.low}, {self.high})"


def memory_mb() -> int:
    """This machine's memory in MB (the most ``--max-memory`` can mean)."""
    try:
        return max(1, os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") // 2**20)
    except (ValueError, OSError, AttributeError):
        return MAX_COUNT // 2**20


SEED = Count(-MAX_COUNT - 1, MAX_COUNT)
PORT = Count(0, 65535)
