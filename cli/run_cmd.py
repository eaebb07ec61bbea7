"""``htn run PLAN``: execute a plan with per-action monitoring on a robot back end."""

from __future__ import annotations

import contextlib
import sys
from types import SimpleNamespace

import click

from htn.api.extras import require_robot_extra
from htn.jshop.language.errors import HtnError
from htn.process import DeadlineExceeded, deadline, silence_stdout

from .options import SEED, TIMEOUT_HELP, Count, Timeout, current_stops
from .output import stdout_is_terminal, warn
from .progress import Phase
from .view_cmd import keep_up, start_run_view, view_options, wait_for_page

RUN_OPTIONS = (
    "plan_file",
    "robot_name",
    "sim",
    "faults",
    "seed",
    "retries",
    "replan",
    "plan_index",
    "domain",
    "problem",
)


@click.command("run")
@click.argument("plan_file", required=False, type=click.Path(dir_okay=False))
@click.option(
    "--robot",
    "robot_name",
    metavar="NAME",
    help="Robot back end: pybullet, symbolic, projection, or one a plugin adds "
    "(entry points 'htn.robots').",
)
@click.option("--sim", is_flag=True, help="Short for --robot pybullet (headless PyBullet).")
@click.option("--gui", is_flag=True, help="Show the simulation in a window (needs a display).")
@click.option(
    "--snapshots",
    type=click.Path(file_okay=False),
    metavar="DIR",
    help="Save a PNG camera image after each action attempt (PyBullet).",
)
@click.option(
    "--faults",
    metavar="KIND=P,...",
    help="Inject faults with these probabilities: slip, nav, detect, moved on "
    "PyBullet; effect on the symbolic robot.",
)
@click.option(
    "--seed",
    type=SEED,
    default=0,
    show_default=True,
    help="Random seed for faults (same seed, same run).",
)
@click.option(
    "--retries",
    multiple=True,
    metavar="OPERATOR=N",
    help="Override retry limits of the domain's .toml, e.g. grasp=3.",
)
@click.option(
    "--replan",
    is_flag=True,
    help="On a failed or aborted action, re-plan the smallest enclosing task "
    "from the observed state, graft it into the tree and go on.",
)
@click.option(
    "--log",
    "log_path",
    type=click.Path(dir_okay=False),
    metavar="FILE.jsonl",
    help="Write every event as a JSON line, flushed as it happens; the first "
    "line (header) records what is needed to re-run it.",
)
@click.option(
    "--from-log",
    "from_log",
    type=click.Path(dir_okay=False),
    metavar="FILE.jsonl",
    help="Re-run what the log's header records (plan, robot, seed, faults, retries, ...).",
)
@click.option(
    "--plan-index",
    type=Count(),
    default=1,
    show_default=True,
    help="Which plan of the file to run.",
)
@click.option(
    "--domain",
    type=click.Path(dir_okay=False),
    help="Domain file (default: the one named in the plan file).",
)
@click.option(
    "--problem",
    type=click.Path(dir_okay=False),
    help="Problem file (default: the one named in the plan file).",
)
@click.option(
    "--functions",
    type=click.Path(dir_okay=False),
    metavar="FILE.py",
    help="User functions for (call ...): needed when the plans were made with "
    "one (the plan file or log names it, and htn checks its SHA-256; it "
    "never imports a file a plan file or log names on its own).",
)
@click.option(
    "--timeout",
    type=Timeout(),
    metavar="SECONDS",
    help=TIMEOUT_HELP + " For a run: the robot holds its pose and the log ends 'interrupted'.",
)
@click.option(
    "--bt-dot",
    "bt_dot",
    type=click.Path(dir_okay=False),
    metavar="FILE.dot",
    help="Write the behaviour tree (py_trees' DOT export) before the run, and "
    "again after it if it was repaired.",
)
@click.option("-q", "--quiet", is_flag=True, help="Print only the summary.")
@view_options
@click.pass_context
def run(ctx, **options):
    """Execute PLAN_FILE (written by 'htn plan -o') with per-action monitoring.

    The plan's task tree (the one the plan file holds; planned again if it
    holds none) runs as a behaviour tree (py_trees) of the same shape; each
    step is an action state machine: execute (with hold-monitors
    on every tick), monitor, report (finished / verified / failed / aborted /
    retrying). With --replan a failed or aborted action is repaired in the
    task tree: the smallest enclosing task that has a plan from the observed
    state is re-planned and grafted in. The whole plan is checked before the
    robot moves. Exit code 0 when every action is verified, 1 when execution
    failed or was aborted, 2 for bad input, 130 on Ctrl-C, 143 on SIGTERM
    (both stop between two ticks; the robot holds its pose).

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
      htn run plan.txt --sim --view          # watch it in a browser (prints the URL)
    """
    o = SimpleNamespace(**options)  # the options as attributes (click's names)
    if o.view_wait and not o.view:
        raise click.UsageError("--view-wait waits for the page of --view: give --view too")
    stops = current_stops()
    try:
        with deadline(stops, o.timeout, stops.started):
            _run(ctx, o, stops)
    except (KeyboardInterrupt, DeadlineExceeded) as exc:  # before the robot runs
        stops.interrupt_exit(exc, now=True)  # now: PyBullet may have been interrupted


def _run(ctx, o: SimpleNamespace, stops) -> None:
    from htn.api.run import prepare

    plan = _from_log(ctx, o, stops) if o.from_log else o.plan_file
    robot_name = _robot_name(o)
    # reading and checking everything, and building a simulated world, can
    # take seconds: a spinner says so (on a terminal, after a second)
    try:
        with Phase(f"reading the plan and building the {robot_name} robot"):
            execution = prepare(
                plan,
                robot=robot_name,
                domain=o.domain,
                problem=o.problem,
                functions=o.functions,
                plan_index=o.plan_index,
                faults=o.faults or "",
                seed=o.seed,
                retries=o.retries,
                replan=o.replan,
                log=o.log_path,
                gui=o.gui,
                stops=stops,
                bt_dot=o.bt_dot,
                snapshots=o.snapshots,
                read=[o.from_log] if o.from_log else [],
            )
    except HtnError as exc:
        raise _as_header_error(exc, o.from_log) from None
    if not o.quiet:
        for note in execution.notes:
            warn(note)
    viewer = start_run_view(o.view_host, o.view_port) if o.view else None  # a port in use: exit 2
    summary = _execute(execution, viewer, o, stops)
    try:
        click.echo(summary.line())
    except BrokenPipeError:  # the reader went away: the exit code still tells
        silence_stdout()
    if summary.result == "interrupted":  # log closed, robot disconnected
        stops.interrupt_exit(stops.cause, now=True)
    if viewer:  # Ctrl-C ends the view; the exit code is the run's
        keep_up(viewer, listen=stops.listen_again)
    sys.exit(0 if summary.result == "verified" else 1)


def _from_log(ctx, o: SimpleNamespace, stops):
    """The run a log records (its plan, robot, seed, ...), which the
    command line may not contradict."""
    given = [
        max(p.opts, key=len) if isinstance(p, click.Option) else p.human_readable_name
        for p in ctx.command.params
        if p.name in RUN_OPTIONS
        and ctx.get_parameter_source(p.name) == click.core.ParameterSource.COMMANDLINE
    ]
    if given:
        raise click.UsageError(
            f"--from-log takes the run from the log; do not give {', '.join(given)} as well"
        )
    from htn.api.run import read_run_log

    # the plan, domain and problem files too, checked to be unchanged
    logged = read_run_log(o.from_log, o.functions, stops)
    o.plan_file, o.robot_name, o.seed, o.replan = (
        logged.plan.path,
        logged.robot,
        logged.seed,
        logged.replan,
    )
    o.faults, o.plan_index, o.retries = logged.faults, logged.plan_index, logged.retries
    o.domain, o.problem, o.functions = logged.domain, logged.problem, logged.functions
    return logged.plan


def _robot_name(o: SimpleNamespace) -> str:
    if o.plan_file is None:
        raise click.UsageError("give a PLAN_FILE (or --from-log FILE.jsonl)")
    if o.sim and o.robot_name not in (None, "pybullet"):
        raise click.UsageError(f"--sim is --robot pybullet; it contradicts --robot {o.robot_name}")
    name = o.robot_name or ("pybullet" if o.sim else None)
    if name is None:
        from htn.api.run import robots

        raise click.UsageError(
            f"choose a robot: --sim (PyBullet) or --robot NAME (known: {', '.join(robots())})"
        )
    require_robot_extra(name, "htn run --sim" if o.sim else f"htn run --robot {name}")
    return name


def _execute(execution, viewer, o: SimpleNamespace, stops):
    """Begin the log, run the tree with the progress shown, end the log:
    the run's summary (interrupted too)."""
    try:
        # the log begins only together with the dispatcher that will end it
        # (an interrupt meanwhile arrives right after, see below)
        with stops.held():
            dispatcher = execution.begin(argv=["htn", *sys.argv[1:]])
            stops.on_emergency(lambda: execution.end_now(str(stops.raised or "stopped")))
        view = None
        if not o.quiet:
            from .tree_view import LiveTreeView, PlainView

            view = LiveTreeView(lambda: dispatcher) if stdout_is_terminal() else PlainView()
            execution.listen(view.event)
        if viewer:
            viewer.attach(execution.log, dispatcher, execution.robot)
            if o.view_wait:
                wait_for_page(viewer)
        stops.watch(execution)
        with view or contextlib.nullcontext():
            summary = execution.execute().summary
        stops.settle()  # the robot holds and the log is complete: shut down in order
    except KeyboardInterrupt as exc:
        if execution.dispatcher is None:  # no log yet: nothing to end
            raise
        # outside the ticks (e.g. while the view starts): the log still
        # ends with the outcome and a summary
        stops.settle()
        summary = execution.interrupted(str(exc)).summary
    except BaseException as exc:
        execution.fail(exc)
        raise
    finally:
        execution.close()
    return summary


# what the log's header gave instead of an option: its errors name the field
HEADER_OPTIONS = {
    "--faults": "faults",
    "--retries": "retries",
    "--plan-index": "plan_index",
    "--robot": "robot",
    "--seed": "seed",
}


def _as_header_error(exc, from_log):
    """An error about a value the log's header gave (``--faults: ...``),
    worded as the header's: ``run.jsonl:1: header field "faults": ...``."""
    option, _, rest = exc.message.partition(": ")
    if not from_log:
        return exc
    field = HEADER_OPTIONS.get(option) or next(
        (f for o, f in HEADER_OPTIONS.items() if exc.message.startswith(o + " ")), None
    )
    if field is None:
        return exc
    text = rest if option in HEADER_OPTIONS else exc.message.split(" ", 2)[-1]
    return HtnError(f'header field "{field}": {text}', from_log, 1)
