"""Option types shared by several commands."""
from __future__ import annotations

import math

import click

TIMEOUT_HELP = ("Wall-clock limit of the whole command in seconds, loading included "
                "(user functions too); 'inf' for none.")


class Timeout(click.ParamType):
    """``--timeout SECONDS``: a positive number of seconds, or ``inf`` (no
    limit, None). Zero, a negative number, NaN or anything unparsable is a
    usage error (exit 2)."""

    name = "seconds"

    def convert(self, value, param, ctx):
        if value is None or isinstance(value, float) and value > 0:
            return None if value is None or math.isinf(value) else value
        text = str(value).strip()
        try:
            seconds = float(text)
        except ValueError:
            self.fail(f"{text[:40]!r} is not a number of seconds (e.g. 10, 0.5 or inf)",
                      param, ctx)
        if math.isnan(seconds) or seconds <= 0:
            self.fail(f"{text[:40]!r}: give a positive number of seconds (or inf for no "
                      "limit)", param, ctx)
        return None if math.isinf(seconds) else seconds
