"""Benchmark: executing a plan on the PyBullet robot in DIRECT mode.

Reports simulated seconds per wall-clock second (the real-time factor) of the
execution itself and of the whole run including building the world, and the
process's peak memory. Target: at least 20x faster than real time. Run::

    python benchmarks/bench_sim.py               # 5 runs of bring_object
    python benchmarks/bench_sim.py --runs 10 --problem guide_robot
    python benchmarks/bench_sim.py --problem set_table_and_clean_up --transformed

Kitchen problems (``(area ...)`` facts) run on the two-armed kitchen robot.
"""

from __future__ import annotations

import resource
import statistics
import time
from pathlib import Path

import click

ROOT = Path(__file__).resolve().parent.parent


@click.command()
@click.option("--problem", default="bring_object", show_default=True)
@click.option("--runs", default=5, show_default=True)
@click.option("--faults", default="", help="e.g. slip=0.3,nav=0.3")
@click.option(
    "--transformed",
    is_flag=True,
    help="Kitchen problems: run the plan after the plan transformations.",
)
def main(problem, runs, faults, transformed):
    """Time plan execution in the simulation; print the real-time factor."""
    from htn.executor.config import load_retries
    from htn.executor.dispatcher import TaskDispatcher
    from htn.executor.log import EventLog
    from htn.jshop import Planner, load_domain, load_problem
    from htn.robot import simulated_robot
    from htn.robot.pybullet_sim import Faults
    from htn.robot.world import is_kitchen_state

    inst = load_problem(str(ROOT / "problems" / f"{problem}.jshop")).instances[0]
    kitchen = is_kitchen_state(inst.state)
    domain = str(ROOT / "domains" / ("kitchen.jshop" if kitchen else "domestic.jshop"))
    dom = load_domain(domain)
    if transformed:
        from htn.transform.framework import Workspace
        from htn.transform.registered import default_framework

        plan = default_framework().apply_all_transformations(Workspace.from_problem(dom, inst)).plan
    else:
        plan = next(Planner(dom, inst, record_trees=True).plans())
    exec_factor, total_factor, sims = [], [], []
    for seed in range(runs):
        t0 = time.perf_counter()
        robot = simulated_robot(inst.state, faults=Faults.parse(faults), seed=seed)
        built = time.perf_counter()
        start_sim = robot.sim_time
        log = EventLog(None, clock=lambda robot=robot: robot.sim_time)
        summary = TaskDispatcher(
            robot, dom, inst, plan.steps, load_retries(domain), log, tree=plan.tree
        ).run()  # the behaviour tree htn run ticks
        done = time.perf_counter()
        sim = robot.sim_time - start_sim
        robot.close()
        exec_factor.append(sim / (done - built))
        total_factor.append(robot.sim_time / (done - t0))
        sims.append(sim)
        click.echo(
            f"run {seed}: {summary.result}, {sim:.1f} s simulated in {done - built:.3f} s "
            f"(+{built - t0:.3f} s to build the world): {exec_factor[-1]:.1f}x real time"
        )
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    click.echo(
        f"\n{problem}: median {statistics.median(exec_factor):.1f} sim-s per wall-s during "
        f"execution (min {min(exec_factor):.1f}), {statistics.median(total_factor):.1f} "
        f"including world building; {statistics.median(sims):.1f} s simulated per run; "
        f"peak memory {peak_mb:.0f} MB"
    )
    ok = min(exec_factor) >= 20
    click.echo(f"at least 20x real time on every run: {ok}")


if __name__ == "__main__":
    main()
