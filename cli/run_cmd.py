"""``htn run PLAN --sim``: execute a plan with monitoring on the simulated robot."""
from __future__ import annotations

import os
import signal
import sys

import click

from jshop.errors import HtnError

from .output import stdout_is_terminal

OUTCOME_STYLE = {"verified": "green", "finished": "cyan", "failed": "bold red",
                 "aborted": "red", "retrying": "yellow", "start": "dim",
                 "replanned": "magenta", "interrupted": "bold red"}


@click.command("run")
@click.argument("plan_file", type=click.Path(dir_okay=False))
@click.option("--sim", is_flag=True, help="Run on the simulated robot (PyBullet, headless).")
@click.option("--gui", is_flag=True, help="Show the simulation in a window (needs a display).")
@click.option("--snapshots", type=click.Path(file_okay=False), metavar="DIR",
              help="Save a PNG camera image after each action attempt.")
@click.option("--faults", metavar="slip=P,nav=P,detect=P,moved=P",
              help="Inject faults with these probabilities.")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Random seed for faults (same seed, same run).")
@click.option("--retries", multiple=True, metavar="OPERATOR=N",
              help="Override retry limits of the domain's .toml, e.g. grasp=3.")
@click.option("--replan", is_flag=True,
              help="On a failed or aborted action, re-plan from the observed state and go on.")
@click.option("--log", "log_path", type=click.Path(dir_okay=False), metavar="FILE.jsonl",
              help="Write every event as a JSON line, flushed as it happens.")
@click.option("--plan-index", type=click.IntRange(min=1), default=1, show_default=True,
              help="Which plan of the file to run.")
@click.option("--domain", type=click.Path(dir_okay=False),
              help="Domain file (default: the one named in the plan file).")
@click.option("--problem", type=click.Path(dir_okay=False),
              help="Problem file (default: the one named in the plan file).")
@click.option("-q", "--quiet", is_flag=True, help="Print only the summary.")
def run(plan_file, sim, gui, snapshots, faults, seed, retries, replan, log_path, plan_index,
        domain, problem, quiet):
    """Execute PLAN_FILE (written by 'htn plan -o') with per-action monitoring.

    Each step runs as an action state machine: execute, monitor, report
    (finished / verified / failed / aborted / retrying). Exit code 0 when every
    action is verified, 1 when execution failed or was aborted, 130 on Ctrl-C.

    The simulated world is built from the problem's initial state: the
    domestic robot (one arm) for problems with locations and furniture, the
    kitchen robot (two arms, tables per area, drawers, trays) for problems
    with (area ...) facts.

    \b
    Examples:
      htn plan domains/domestic.jshop problems/bring_object.jshop -o plan.txt
      htn run plan.txt --sim
      htn run plan.txt --sim --faults slip=0.5,nav=0.3 --seed 4 --log run.jsonl
      htn run plan.txt --sim --faults moved=1 --replan
      htn transform domains/kitchen.jshop problems/set_table_and_clean_up.jshop -o t.txt
      htn run t.txt --sim
    """
    from executor.config import load_retries, parse_overrides
    from executor.dispatcher import TaskDispatcher
    from executor.log import EventLog
    from jshop.functions import FunctionTable
    from jshop.parser import load_domain, load_problem
    from jshop.planfile import read_plan_file
    from robot.pybullet_sim import Faults

    pf = read_plan_file(plan_file)
    domain = domain or pf.domain
    problem = problem or pf.problem
    if not domain or not problem:
        raise HtnError("the plan file names no domain or problem (write it with 'htn plan -o', "
                       "or give --domain and --problem)", plan_file)
    if plan_index > len(pf.plans):
        raise HtnError(f"--plan-index {plan_index}: the file holds {len(pf.plans)} plan(s)",
                       plan_file)
    if not sim:
        raise click.UsageError("choose where to run the plan: --sim (the PyBullet simulation)")
    if gui and not os.environ.get("DISPLAY"):
        raise click.UsageError("--gui needs a display (DISPLAY is not set); run headless without it")
    fault_cfg = Faults.parse(faults)
    table = FunctionTable()
    dom = load_domain(domain, table)
    prob = load_problem(problem, table)
    instance = prob.instances[0]
    steps = pf.plans[plan_index - 1].steps
    _check_steps(steps, dom, plan_file)
    limits = load_retries(domain)
    limits.update(parse_overrides(retries))

    from robot import simulated_robot
    robot = simulated_robot(instance.state, gui=gui, faults=fault_cfg, seed=seed)
    if snapshots:   # only once the world could be built from the problem
        os.makedirs(snapshots, exist_ok=True)
    log = EventLog(log_path, clock=lambda: robot.sim_time)
    view = None
    if not quiet:
        view = _LiveView() if stdout_is_terminal() else _PlainView()
        log.listeners.append(view.event)
    if snapshots:
        log.listeners.append(_snapshotter(robot, snapshots))
    dispatcher = TaskDispatcher(robot, dom, instance, steps, limits, log,
                                replan=replan, functions=table)
    try:
        if isinstance(view, _LiveView):
            with view:
                summary = dispatcher.run()
        else:
            summary = dispatcher.run()
        if summary.result == "interrupted":
            # the robot holds and the log is complete: shut down in order,
            # ignoring a second Ctrl-C
            signal.signal(signal.SIGINT, signal.SIG_IGN)
    finally:
        log.close()
        robot.close()
    click.echo(f"{summary.result}: {summary.verified} of {summary.steps} steps verified, "
               f"{summary.retries} retries, {summary.replans} replans, "
               f"{summary.sim_time:.1f} s simulated"
               + (f"; stopped at {summary.failed_step}" if summary.failed_step else ""))
    if summary.result == "interrupted":
        # Log closed, robot disconnected: leave at once. Interpreter shutdown
        # after a Ctrl-C inside PyBullet was seen (rarely) to end by SIGINT
        # instead of exit code 130.
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(130)
    sys.exit(0 if summary.result == "verified" else 1)


def _check_steps(steps, domain, plan_file) -> None:
    """Every step must be an operator of the domain, with its arity, and have an
    action state machine unless it is internal (!!)."""
    from executor.actions import machine_for
    for s in steps:
        ops = domain.operators.get(s.name)
        if not ops:
            raise HtnError(f"unknown operator {s.name}: the domain has no such operator",
                           plan_file, s.line, 1)
        if all(len(o.head.args) != len(s.args) for o in ops):
            raise HtnError(f"{s.name} takes {len(ops[0].head.args)} arguments, given "
                           f"{len(s.args)}", plan_file, s.line, 1)
        if not s.internal and machine_for(s.name, domain.name) is None:
            raise HtnError(f"no action state machine is registered for {s.name}",
                           plan_file, s.line, 1)


def _snapshotter(robot, folder):
    def on_event(rec):
        if rec["event"] in ("verified", "failed", "aborted") and rec["step"] is not None:
            name = f"step{rec['step'] + 1:02d}_try{rec['attempt'] or 1}_{rec['event']}.png"
            robot.snapshot(os.path.join(folder, name))
    return on_event


class _PlainView:
    """One line per action outcome (when stdout is not a terminal)."""

    def event(self, rec) -> None:
        if rec["event"] in ("verified", "failed", "aborted", "retrying", "replanned", "interrupted"):
            step = "" if rec["step"] is None else f"{rec['step'] + 1:>2} "
            click.echo(f"{step}{rec['event']:<11} {rec['action'] or ''}  "
                       f"[try {rec['attempt'] or '-'}, t={rec['t']:.1f}s] {rec['detail']}")


class _LiveView:
    """A rich live table: one row per action with its outcome, attempt and duration."""

    def __init__(self):
        from rich.console import Console
        from rich.live import Live
        self.rows: dict = {}
        self.console = Console()
        self.live = Live(self._table(), console=self.console, refresh_per_second=10,
                         transient=False)

    def __enter__(self):
        self.live.__enter__()
        return self

    def __exit__(self, *exc):
        self.live.update(self._table())
        return self.live.__exit__(*exc)

    def event(self, rec) -> None:
        if rec["step"] is None or rec["event"] == "summary":
            return
        key = rec["step"], rec["action"]
        row = self.rows.setdefault(key, {"action": rec["action"], "start": rec["t"],
                                         "event": "", "attempt": 1, "detail": ""})
        if rec["event"] == "feedback":
            return
        row.update(event=rec["event"], attempt=rec["attempt"] or row["attempt"],
                   detail=rec["detail"], end=rec["t"])
        self.live.update(self._table())

    def _table(self):
        from rich.markup import escape
        from rich.table import Table
        t = Table(title="execution", expand=False)
        for col in ("#", "action", "outcome", "try", "time", "detail"):
            t.add_column(col, overflow="fold")
        for (step, _), row in self.rows.items():
            style = OUTCOME_STYLE.get(row["event"], "")
            t.add_row(str(step + 1), escape(row["action"] or ""),
                      f"[{style}]{row['event']}[/{style}]" if style else row["event"],
                      str(row["attempt"]), f"{row.get('end', row['start']) - row['start']:.1f}s",
                      escape(row["detail"][:60]))
        return t
