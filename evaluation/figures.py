"""Figures of an evaluation in the manner of the plan-transformations paper's
Fig. 8 and 9 (bars of each metric for the original and the transformed plan),
plus the distributions of the per-run metrics.

Every figure is written as PNG (300 dpi), PDF and SVG, with fixed metadata so
that the same evaluation gives the same files. The original and the
transformed plan have one colour each in every panel of every figure
(Okabe-Ito blue and vermilion, told apart also in grey and by colour-blind
readers). Error bars say what they are: one standard deviation of the runs,
clipped at 0, for distances and actions; the Wilson 95% interval of the
pooled failure proportion, which stays within [0, 1].
"""

from __future__ import annotations

import os
from typing import Any

from .statistics import METRIC_NAMES, Comparison, applied_rules, format_change, format_p

SERIES = {"original": ("original plan", "#0072B2"), "transformed": ("transformed plan", "#D55E00")}
FORMATS = ("png", "pdf", "svg")
DPI = 300
# rc keys (matplotlib types them as a Literal of every rc name)
STYLE: dict[Any, Any] = {
    "font.size": 8,
    "axes.titlesize": 8.5,
    "axes.labelsize": 8,
    "xtick.labelsize": 7.5,
    "ytick.labelsize": 7.5,
    "legend.fontsize": 7.5,
    "figure.titlesize": 9.5,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "pdf.fonttype": 42,  # TrueType in the PDF, as publishers ask
    "svg.fonttype": "none",  # SVG text stays editable text
    "svg.hashsalt": "htn-evaluate",  # SVG element ids the same on every run
}
METADATA = {
    "png": {"Software": None},
    "pdf": {"CreationDate": None, "Producer": None},
    "svg": {"Date": None},
}
LABELS = {
    "navigation": "base travel per run (m)",
    "manipulation": "gripper travel per run (m)",
    "actions": "action attempts per run",
    "failures": "failed / attempted actions",
}


def plot(comp: Comparison, folder: str) -> list[str]:
    """Write ``NAME_metrics`` and ``NAME_distributions`` into ``folder``, each
    in every format; returns the files written."""
    import matplotlib
    from cycler import cycler

    os.makedirs(folder, exist_ok=True)
    name = os.path.splitext(os.path.basename(comp.problem))[0]
    # colours are always given; the cycle's only use left is error-bar caps
    with matplotlib.rc_context({**STYLE, "axes.prop_cycle": cycler(color=["black"])}):
        files = _save(_metrics_figure(comp, name), os.path.join(folder, f"{name}_metrics"))
        files += _save(
            _distributions_figure(comp, name), os.path.join(folder, f"{name}_distributions")
        )
    return files


def _save(fig, stem: str) -> list[str]:
    """The figure in every format, each file replaced whole (never a
    half-drawn figure where an earlier one was)."""
    from htn.files import atomic_write

    paths = []
    for fmt in FORMATS:
        path = f"{stem}.{fmt}"
        with atomic_write(path, "--plot", binary=True) as out:
            fig.savefig(out.fh, format=fmt, dpi=DPI, metadata=METADATA[fmt])
        paths.append(path)
    return paths


def _runs_title(comp: Comparison, name: str) -> str:
    from .runs import MEASURES

    what = MEASURES[comp.robot].description
    title = (
        f"{name}: {comp.runs} {what} run{'s' if comp.runs != 1 else ''} of each plan; "
        f"applied: {applied_rules(comp.applied)}"
    )
    # a run a fault stopped counts what it did until then: say how many did
    results = comp.results()
    verified = {side: results[side].get("verified", 0) for side in results}
    if any(verified[side] < sum(results[side].values()) for side in results):
        title += "\nruns verified: " + ", ".join(
            f"{side} {verified[side]} of {sum(results[side].values())}" for side in results
        )
    return title


def _metrics_figure(comp: Comparison, name: str):
    from matplotlib.figure import Figure
    from matplotlib.ticker import PercentFormatter

    stats = comp.metrics()
    fig = Figure(figsize=(7.2, 2.7), layout="constrained")
    axes = fig.subplots(1, len(METRIC_NAMES))
    sides = list(SERIES)
    for ax, metric in zip(axes, METRIC_NAMES):
        s = stats[metric]
        if metric == "failures":
            heights = [s[side]["rate"] for side in sides]
            errors = [_interval(s[side]["rate"], s[side]["wilson95"]) for side in sides]
            ax.yaxis.set_major_formatter(PercentFormatter(xmax=1.0, decimals=1))
        else:
            heights = [s[side]["mean"] for side in sides]
            errors = [_sd_bar(s[side]["mean"], s[side]["sd"]) for side in sides]
        for x, side, height, (low, high) in zip(range(2), sides, heights, errors):
            ax.bar(x, height or 0.0, width=0.62, color=SERIES[side][1])
            if high:
                ax.errorbar(
                    x,
                    height,
                    yerr=[[low], [high]],
                    fmt="none",
                    ecolor="black",
                    elinewidth=0.9,
                    capsize=4,
                )
        ax.set_xticks(range(2), ["original", "transformed"])
        ax.set_ylim(bottom=0)
        ax.set_ylabel(LABELS[metric])
        if metric == "failures":  # the bars are the pooled rates: say them
            change = " \u2192 ".join(_percent(h) for h in heights)
        else:
            change = format_change(s["change_pct"])
        ax.set_title(f"{metric}\n{change}, p {_p_text(s['p_value'])}")
    fig.suptitle(_runs_title(comp, name))
    fig.supxlabel(
        "Bars: mean over runs (a run a fault stopped counts what it did until then); "
        "error bars: \u00b11 SD of the runs (clipped at 0).\n"
        "Failures: pooled over all runs, error bars: Wilson 95% CI.\n"
        "Change: of the mean; p: Welch's two-sided t-test on per-run values "
        "(n/a: fewer than 2 runs or no variance).",
        fontsize=6.5,
    )
    return fig


def _percent(rate) -> str:
    return "n/a" if rate is None else f"{rate:.1%}"


def _p_text(p) -> str:
    text = format_p(p)
    return text if text.startswith("<") else f"= {text}"


def _sd_bar(mean, sd) -> tuple:
    """(below, above) of a bar of one SD that does not go below zero."""
    if mean is None or sd is None:
        return 0.0, 0.0
    return min(sd, max(mean, 0.0)), sd


def _interval(rate, interval) -> tuple:
    if rate is None or interval is None:
        return 0.0, 0.0
    low, high = interval
    return rate - low, high - rate


def _distributions_figure(comp: Comparison, name: str):
    from matplotlib.figure import Figure

    shown = ("navigation", "manipulation", "actions")
    fig = Figure(figsize=(7.2, 2.5), layout="constrained")
    axes = fig.subplots(1, len(shown))
    for ax, metric in zip(axes, shown):
        values = {side: [r[metric] for r in getattr(comp, side)] for side in SERIES}
        edges = _shared_bins(list(values.values()), metric == "actions")
        for side, (label, colour) in SERIES.items():
            ax.hist(
                values[side], bins=edges, histtype="step", linewidth=1.3, color=colour, label=label
            )
            if values[side]:
                mean = sum(values[side]) / len(values[side])
                ax.axvline(mean, color=colour, linestyle="--", linewidth=0.9)
        ax.set_xlabel(LABELS[metric])
        ax.set_ylabel("runs")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=2, frameon=False)
    fig.suptitle(
        _runs_title(comp, name) + "\nper-run distributions, the same bins for "
        "both plans; dashed: means"
    )
    return fig


def _shared_bins(series: list, integers: bool, most: int = 40):
    """Bin edges shared by both plans: unit bins for counts; else the width
    numpy's automatic rule gives the finer of the two plans' values (so two
    narrow, far apart distributions each keep their shape), at most ``most``
    bins over both. Values that differ by rounding only (physics runs
    without faults) count as one value."""
    import numpy as np

    values = [v for vs in series for v in vs]
    low, high = (min(values), max(values)) if values else (0.0, 0.0)
    if integers:
        return np.arange(np.floor(low) - 0.5, np.ceil(high) + 1.0, 1.0)

    def spread(vs) -> bool:
        return max(vs) - min(vs) > 1e-9 * max(1.0, abs(max(vs)), abs(min(vs)))

    if not values or not spread(values):
        return np.array([low - 0.5, high + 0.5])  # numpy's rule for one value
    widths = [
        np.diff(np.histogram_bin_edges(vs, bins="auto"))[0]
        for vs in series
        if len(vs) > 1 and spread(vs)
    ]
    step = min(widths) if widths else (high - low) / 10
    return np.linspace(low, high, min(most, max(1, int(np.ceil((high - low) / step)))) + 1)
