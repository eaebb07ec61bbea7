"""Projected runs of a plan with and without transformation (the paper's
evaluation, Section IV-A): metrics per run, summary statistics and a Welch
t-test per metric."""
from __future__ import annotations

import statistics
from dataclasses import dataclass, field
from typing import Optional

from htn.executor.config import load_retries
from htn.executor.dispatcher import TaskDispatcher
from htn.executor.log import EventLog
from htn.jshop import syntax as S
from htn.robot.projection import FailureRates, ProjectionRobot, world_from_atoms

METRIC_NAMES = ("navigation", "manipulation", "actions", "failures")


def project(domain: S.Domain, instance: S.ProblemInstance, steps, seed: int,
            rates: Optional[FailureRates] = None, retries: Optional[dict] = None) -> dict:
    """Execute ``steps`` once on the projection robot; metrics of the run.

    ``failures`` is the share of action attempts that failed (0..1)."""
    robot = ProjectionRobot(world_from_atoms(instance.state), seed=seed, failures=rates)
    log = EventLog(None, clock=lambda: robot.sim_time)
    summary = TaskDispatcher(robot, domain, instance, steps, retries or {}, log).run()
    m = robot.metrics
    outcomes = {e["step"] - 1: e["event"] for e in log.events   # log steps are 1-based
                if e["event"] in ("verified", "aborted", "failed") and e["step"] is not None}
    return {"navigation": m.navigation, "manipulation": m.manipulation,
            "actions": float(m.actions), "failures": m.failures / max(m.actions, 1),
            "sim_time": m.sim_time, "result": summary.result, "outcomes": outcomes}


def projected_tree(domain: S.Domain, instance: S.ProblemInstance, plan, seed: int = 0,
                   retries: Optional[dict] = None):
    """The plan's task tree annotated with the outcomes of one projected run."""
    from htn.jshop.tree import annotate
    run = project(domain, instance, plan.steps, seed, retries=retries)
    return annotate(plan.tree, run["outcomes"]), run


@dataclass
class Comparison:
    problem: str
    runs: int
    applied: list
    original: list = field(default_factory=list)      # per-run metric dicts
    transformed: list = field(default_factory=list)

    def metrics(self) -> dict:
        from scipy import stats
        out = {}
        for name in METRIC_NAMES:
            a = [r[name] for r in self.original]
            b = [r[name] for r in self.transformed]
            ma, mb = statistics.fmean(a), statistics.fmean(b)
            p = float(stats.ttest_ind(a, b, equal_var=False).pvalue) if len(a) > 1 else float("nan")
            out[name] = {
                "original": {"mean": ma, "sd": statistics.stdev(a) if len(a) > 1 else 0.0},
                "transformed": {"mean": mb, "sd": statistics.stdev(b) if len(b) > 1 else 0.0},
                "change_pct": (mb - ma) / ma * 100 if ma else float("nan"),
                "p_value": p,
            }
        return out


# ------------------------------------------------------------------ runs

_CACHE: dict = {}


def _load(domain_path: str, problem_path: str):
    key = (domain_path, problem_path)
    if key not in _CACHE:
        from htn.jshop import load_domain, load_problem
        from .framework import Workspace, default_framework
        dom = load_domain(domain_path)
        inst = load_problem(problem_path).instances[0]
        ws = Workspace.from_problem(dom, inst)
        original = ws.plan
        default_framework().apply_all_transformations(ws)
        _CACHE[key] = (dom, inst, original, ws, load_retries(domain_path))
    return _CACHE[key]


def _run_pair(args) -> tuple[dict, dict]:
    domain_path, problem_path, seed = args
    dom, inst, original, ws, retries = _load(domain_path, problem_path)
    return (project(dom, inst, original.steps, seed, retries=retries),
            project(dom, inst, ws.plan.steps, seed, retries=retries))


def compare(domain_path: str, problem_path: str, runs: int, seed: int = 0, workers: int = 1,
            progress=None) -> Comparison:
    """Project the plan and its transformed version ``runs`` times each (run i
    uses seed ``seed + i`` for both), in ``workers`` processes."""
    dom, inst, original, ws, _ = _load(domain_path, problem_path)
    comp = Comparison(problem_path, runs, [r for r, s, _ in ws.log if s == "applied"])
    jobs = [(domain_path, problem_path, seed + i) for i in range(runs)]
    if workers > 1:
        import multiprocessing
        with multiprocessing.get_context("spawn").Pool(workers) as pool:
            results = pool.imap(_run_pair, jobs, chunksize=max(1, runs // (workers * 8)))
            for a, b in results:
                comp.original.append(a)
                comp.transformed.append(b)
                if progress:
                    progress()
    else:
        for job in jobs:
            a, b = _run_pair(job)
            comp.original.append(a)
            comp.transformed.append(b)
            if progress:
                progress()
    return comp


UNITS = {"navigation": "m per run", "manipulation": "m per run", "actions": "per run",
         "failures": "failed / attempted actions"}


def plot(comp: Comparison, folder: str) -> list[str]:
    """Bar charts of each metric's mean and standard deviation, with and
    without transformation (like the paper's Fig. 8 and 9). Returns the files."""
    import os
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    os.makedirs(folder, exist_ok=True)
    stats = comp.metrics()
    name = os.path.splitext(os.path.basename(comp.problem))[0]
    fig, axes = plt.subplots(1, len(METRIC_NAMES), figsize=(13, 3.4))
    for ax, metric in zip(axes, METRIC_NAMES):
        s = stats[metric]
        means = [s["original"]["mean"], s["transformed"]["mean"]]
        sds = [s["original"]["sd"], s["transformed"]["sd"]]
        ax.bar(["original", "transformed"], means, yerr=sds, capsize=6,
               color=["#9aa5b1", "#2f7ebc"])
        ax.set_title(f"{metric}\n{s['change_pct']:+.1f}%, p={s['p_value']:.2g}", fontsize=10)
        ax.set_ylabel(UNITS[metric])
        ax.set_ylim(bottom=0)   # a rate or distance below zero would only be the error bar
    fig.suptitle(f"{name}: {comp.runs} projected runs each; applied: "
                 f"{', '.join(comp.applied) or 'none'}", fontsize=11)
    fig.tight_layout()
    path = os.path.join(folder, f"{name}_metrics.png")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(5, 3.4))
    ax.hist([r["navigation"] for r in comp.original], bins=25, alpha=0.6, label="original")
    ax.hist([r["navigation"] for r in comp.transformed], bins=25, alpha=0.6, label="transformed")
    ax.set_xlabel("navigation distance per run (m)")
    ax.legend()
    fig.tight_layout()
    path2 = os.path.join(folder, f"{name}_navigation.png")
    fig.savefig(path2, dpi=110)
    plt.close(fig)
    return [path, path2]
