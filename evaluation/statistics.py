"""Summary statistics of an evaluation: per metric, the mean and standard
deviation over runs of each plan, the change of the mean and Welch's t-test
(two-sided, unequal variances; the paper uses "a standard T-test"); for the
failure rate also the pooled proportion of failed attempts with its Wilson
95% interval.

A statistic that is undefined is ``None`` (JSON ``null``, shown as "n/a"),
never NaN: a standard deviation of fewer than two runs, a p-value with fewer
than two runs on a side or no variance on either (none, or so little that
scipy reports precision loss), a change from a mean of 0.
"""

from __future__ import annotations

import math
import statistics
import warnings
from collections import Counter
from dataclasses import dataclass, field

METRIC_NAMES = ("navigation", "manipulation", "actions", "failures")
UNDERFLOW = 1e-300  # p-values below this are shown as "< 1e-300"


@dataclass
class Comparison:
    """The records of an evaluation's runs, one list per plan in run order."""

    problem: str
    runs: int
    applied: list
    original: list = field(default_factory=list)  # per-run records (dicts)
    transformed: list = field(default_factory=list)
    robot: str = "projection"
    workers: int = 1
    seconds: float = 0.0  # wall time of the runs

    @property
    def runs_per_s(self) -> float:
        """Plan executions (both plans count) per wall-clock second."""
        done = len(self.original) + len(self.transformed)
        return done / self.seconds if self.seconds > 0 else 0.0

    def results(self) -> dict:
        """How the runs of each plan ended (verified, aborted, failed, ...).
        Every run counts in the metrics, a stopped one with what it did
        until it stopped."""
        return {
            side: dict(Counter(r["result"] for r in getattr(self, side)))
            for side in ("original", "transformed")
        }

    def metrics(self) -> dict:
        out: dict = {}
        for name in METRIC_NAMES:
            a = [r[name] for r in self.original]
            b = [r[name] for r in self.transformed]
            ma, mb = _mean(a), _mean(b)
            out[name] = {
                "original": {"mean": ma, "sd": _sd(a)},
                "transformed": {"mean": mb, "sd": _sd(b)},
                "change_pct": (mb - ma) / ma * 100 if ma and mb is not None else None,
                "p_value": welch_p(a, b),
            }
        for side in ("original", "transformed"):
            out["failures"][side].update(pooled_failures(getattr(self, side)))
        return out


def _mean(values) -> float | None:
    return statistics.fmean(values) if values else None


def _sd(values) -> float | None:
    return statistics.stdev(values) if len(values) > 1 else None


def welch_p(a, b) -> float | None:
    """Two-sided p-value of Welch's t-test, or None where it is undefined."""
    if len(a) < 2 or len(b) < 2 or (statistics.pvariance(a) == 0 == statistics.pvariance(b)):
        return None
    from scipy import stats

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        p = float(stats.ttest_ind(a, b, equal_var=False).pvalue)
    # scipy warns of precision loss when the samples are nearly identical
    # (e.g. physics runs that differ by rounding only): the p-value is then
    # noise, NaN or absurdly small, and is not a result
    if math.isnan(p) or any(issubclass(w.category, RuntimeWarning) for w in caught):
        return None
    return p


def pooled_failures(records) -> dict:
    """Failed and attempted actions over all runs, their proportion and its
    Wilson score 95% interval (within [0, 1] by construction)."""
    failed = sum(r["failed"] for r in records)
    attempts = sum(r["actions"] for r in records)
    if not attempts:
        return {"failed": failed, "attempts": attempts, "rate": None, "wilson95": None}
    from scipy import stats

    ci = stats.binomtest(failed, attempts).proportion_ci(0.95, method="wilson")
    return {
        "failed": failed,
        "attempts": attempts,
        "rate": failed / attempts,
        "wilson95": [float(ci.low), float(ci.high)],
    }


# ------------------------------------------------------------------ display


def format_p(p: float | None) -> str:
    if p is None:
        return "n/a"
    return f"< {UNDERFLOW:.0e}" if p < UNDERFLOW else f"{p:.2g}"


def format_change(pct: float | None) -> str:
    return "n/a" if pct is None else f"{pct:+.1f}%".replace("-", "\u2212")


def applied_rules(applied: list) -> str:
    """Each applied rule once, with its count: "both-hands \u00d72", "tray, container"."""
    counts = Counter(applied)
    return ", ".join(f"{rule} \u00d7{n}" if n > 1 else rule for rule, n in counts.items()) or "none"
