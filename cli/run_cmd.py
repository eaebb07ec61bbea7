"""``htn run PLAN``: execute a plan with per-action monitoring on a robot back end."""
from __future__ import annotations

import os
import signal
import sys

import click

from htn.jshop.errors import HtnError

from .extras import require_extra
from .output import stdout_is_terminal

OUTCOME_STYLE = {"verified": "green", "finished": "cyan", "failed": "bold red",
                 "aborted": "red", "retrying": "yellow", "start": "dim",
                 "replanned": "magenta", "interrupted": "bold red"}


RUN_OPTIONS = ("plan_file", "robot_name", "sim", "faults", "seed", "retries", "replan",
               "plan_index", "domain", "problem", "functions")


@click.command("run")
@click.argument("plan_file", required=False, type=click.Path(dir_okay=False))
@click.option("--robot", "robot_name", metavar="NAME",
              help="Robot back end: pybullet, symbolic, projection, or one a plugin adds "
                   "(entry points 'htn.robots').")
@click.option("--sim", is_flag=True, help="Short for --robot pybullet (headless PyBullet).")
@click.option("--gui", is_flag=True, help="Show the simulation in a window (needs a display).")
@click.option("--snapshots", type=click.Path(file_okay=False), metavar="DIR",
              help="Save a PNG camera image after each action attempt (PyBullet).")
@click.option("--faults", metavar="KIND=P,...",
              help="Inject faults with these probabilities: slip, nav, detect, moved on "
                   "PyBullet; effect on the symbolic robot.")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Random seed for faults (same seed, same run).")
@click.option("--retries", multiple=True, metavar="OPERATOR=N",
              help="Override retry limits of the domain's .toml, e.g. grasp=3.")
@click.option("--replan", is_flag=True,
              help="On a failed or aborted action, re-plan from the observed state and go on.")
@click.option("--log", "log_path", type=click.Path(dir_okay=False), metavar="FILE.jsonl",
              help="Write every event as a JSON line, flushed as it happens; the first "
                   "line (header) records what is needed to re-run it.")
@click.option("--from-log", "from_log", type=click.Path(dir_okay=False), metavar="FILE.jsonl",
              help="Re-run what the log's header records (plan, robot, seed, faults, "
                   "retries, ...).")
@click.option("--plan-index", type=click.IntRange(min=1), default=1, show_default=True,
              help="Which plan of the file to run.")
@click.option("--domain", type=click.Path(dir_okay=False),
              help="Domain file (default: the one named in the plan file).")
@click.option("--problem", type=click.Path(dir_okay=False),
              help="Problem file (default: the one named in the plan file).")
@click.option("--functions", type=click.Path(dir_okay=False), metavar="FILE.py",
              help="User functions for (call ...) (default: the plan file's, if any).")
@click.option("-q", "--quiet", is_flag=True, help="Print only the summary.")
@click.pass_context
def run(ctx, plan_file, robot_name, sim, gui, snapshots, faults, seed, retries, replan,
        log_path, from_log, plan_index, domain, problem, functions, quiet):
    """Execute PLAN_FILE (written by 'htn plan -o') with per-action monitoring.

    Each step runs as an action state machine: execute, monitor, report
    (finished / verified / failed / aborted / retrying). Exit code 0 when every
    action is verified, 1 when execution failed or was aborted, 130 on Ctrl-C.

    Robots: 'pybullet' (--sim; the 'sim' extra) builds a simulated world from
    the problem's initial state: the domestic robot (one arm) for problems with
    locations and furniture, the kitchen robot (two arms, tables per area,
    drawers, trays) for problems with (area ...) facts. 'symbolic' runs any
    domain's plan against the domain's own operators. 'projection' is the
    fast kinematic robot of the plan-transformations paper.

    \b
    Examples:
      htn plan domains/domestic.jshop problems/bring_object.jshop -o plan.txt
      htn run plan.txt --sim
      htn run plan.txt --sim --faults slip=0.5,nav=0.3 --seed 4 --log run.jsonl
      htn run --from-log run.jsonl          # the same run again
      htn run plan.txt --sim --faults moved=1 --replan
      htn run plan.txt --robot symbolic --faults effect=0.2
    """
    from htn.executor.actions import machine_for
    from htn.executor.config import load_retries, parse_overrides
    from htn.executor.dispatcher import TaskDispatcher
    from htn.executor.log import EventLog
    from htn.jshop.functions import FunctionTable
    from htn.jshop.parser import load_domain, load_problem
    from htn.jshop.planfile import read_plan_file
    from htn.jshop.validate import check_steps
    from htn.robot.backends import RobotRequest, backends, make_robot
    from htn.robot.interface import Robot

    if from_log:
        given = [n for n in RUN_OPTIONS
                 if ctx.get_parameter_source(n) == click.core.ParameterSource.COMMANDLINE]
        if given:
            raise click.UsageError(f"--from-log takes the run from the log; do not give "
                                   f"{', '.join(given)} as well")
        rec = read_header(from_log)
        plan_file, robot_name, seed, replan = rec["plan"], rec["robot"], rec["seed"], rec["replan"]
        faults, plan_index = rec["faults"], rec["plan_index"]
        domain, problem, functions = rec["domain"], rec["problem"], rec.get("functions")
        retries = [",".join(f"{k}={v}" for k, v in rec["retries"].items())] if rec["retries"] else []
        _check_digest(plan_file, rec.get("plan_sha256"), from_log)
    if plan_file is None:
        raise click.UsageError("give a PLAN_FILE (or --from-log FILE.jsonl)")
    if sim and robot_name not in (None, "pybullet"):
        raise click.UsageError(f"--sim is --robot pybullet; it contradicts --robot {robot_name}")
    robot_name = robot_name or ("pybullet" if sim else None)
    known = backends()
    if robot_name is None:
        raise click.UsageError("choose a robot: --sim (PyBullet) or --robot NAME "
                               f"(known: {', '.join(sorted(known))})")
    backend = known.get(robot_name)
    if backend is not None and backend.extra:
        require_extra(backend.extra, "htn run --sim" if sim else f"htn run --robot {robot_name}")
    if gui and not os.environ.get("DISPLAY"):
        raise click.UsageError("--gui needs a display (DISPLAY is not set); run headless without it")
    pf = read_plan_file(plan_file)
    domain = domain or pf.domain
    problem = problem or pf.problem
    functions = functions or pf.file("functions")
    if not domain or not problem:
        raise HtnError("the plan file names no domain or problem (write it with 'htn plan -o', "
                       "or give --domain and --problem)", plan_file)
    if plan_index > len(pf.plans):
        raise HtnError(f"--plan-index {plan_index}: the file holds {len(pf.plans)} plan(s)",
                       plan_file)
    table = FunctionTable()
    if functions:
        table.load_file(functions)
    dom = load_domain(domain, table)
    prob = load_problem(problem, table)
    instance = prob.instances[0]
    steps = pf.plans[plan_index - 1].steps
    check_steps(dom, steps, plan_file)
    limits = load_retries(domain)
    limits.update(parse_overrides(retries))

    robot = make_robot(robot_name, RobotRequest(dom, instance, faults or "", seed, gui, table))
    try:
        for s in steps:
            if not s.internal and machine_for(s.name, dom.name, robot) is None:
                raise HtnError(f"no action state machine is registered for {s.name} "
                               f"(try --robot symbolic, or add one: entry points 'htn.actions')",
                               plan_file, s.line, 1)
        if snapshots and type(robot).snapshot is Robot.snapshot:
            raise click.UsageError(f"--snapshots: the {robot_name} robot has no camera")
    except BaseException:
        robot.close()
        raise
    if snapshots:   # only once the world could be built from the problem
        os.makedirs(snapshots, exist_ok=True)
    log = EventLog(log_path, clock=lambda: robot.sim_time)
    log.emit(None, None, "header", None, "", **run_header(
        plan_file, plan_index, domain, problem, functions, robot_name, seed, faults or "",
        limits, replan))
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


def run_header(plan_file, plan_index, domain, problem, functions, robot, seed, faults,
               retries, replan) -> dict:
    """What a log's first event records: enough to run the same thing again."""
    import hashlib
    import platform
    from importlib.metadata import PackageNotFoundError, version

    import htn

    def installed(name):
        try:
            return version(name)
        except PackageNotFoundError:
            return None
    with open(plan_file, "rb") as fh:
        digest = hashlib.sha256(fh.read()).hexdigest()
    absolute = lambda p: os.path.abspath(p) if p else None  # noqa: E731
    return {"htn": htn.__version__, "argv": ["htn", *sys.argv[1:]],
            "plan": absolute(plan_file), "plan_sha256": digest, "plan_index": plan_index,
            "domain": absolute(domain), "problem": absolute(problem),
            "functions": absolute(functions), "robot": robot, "seed": seed, "faults": faults,
            "retries": dict(sorted(retries.items())), "replan": replan,
            "python": platform.python_version(), "pybullet": installed("pybullet")}


HEADER_KEYS = ("plan", "plan_index", "domain", "problem", "robot", "seed", "faults",
               "retries", "replan")


def read_header(path: str) -> dict:
    """The header event of a log written by ``htn run --log``."""
    import json
    if not os.path.isfile(path):
        raise HtnError("no such log file", path)
    try:
        with open(path, encoding="utf-8") as fh:
            first = fh.readline()
        rec = json.loads(first)
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise HtnError(f"not a log of htn run --log: {exc}", path, 1, 1)
    if not isinstance(rec, dict) or rec.get("event") != "header":
        raise HtnError("not a log of htn run --log: its first line is no header event",
                       path, 1, 1)
    missing = [k for k in HEADER_KEYS if k not in rec]
    if missing:
        raise HtnError(f"the header lacks {', '.join(missing)}", path, 1, 1)
    return rec


def _check_digest(plan_file: str, digest, log_path: str) -> None:
    import hashlib
    if not os.path.isfile(plan_file):
        raise HtnError(f"the plan file of this run is missing: {plan_file}", log_path, 1, 1)
    with open(plan_file, "rb") as fh:
        now = hashlib.sha256(fh.read()).hexdigest()
    if digest and now != digest:
        raise HtnError(f"the plan file {plan_file} has changed since this run (SHA-256 "
                       f"{now[:12]}..., the log says {digest[:12]}...)", log_path, 1, 1)


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
