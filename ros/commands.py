"""``htn ros``: the ROS 2 commands (the ``ros`` extra). They are found by
the command line through the entry-point group ``htn.commands`` (the command
line imports no ROS), and parse, call :mod:`htn.ros.node` and print."""

from __future__ import annotations

import re
import sys
from importlib.util import find_spec

import click

from htn.jshop.language.errors import HtnError

MISSING = (
    "needs the ros extra (ROS 2 Jazzy from PyPI): pip install 'htn[ros]'; the first "
    "use builds its interface packages once (a C compiler, cmake and the Python headers "
    "are needed)"
)


@click.group("ros")
def ros():
    """ROS 2: htn as a planning-and-execution node, and a client for it.

    \b
    Needs the ros extra: pip install 'htn[ros]' (ROS 2 Jazzy's wheels; no
    ROS install). Nodes on one machine find each other by ROS_DOMAIN_ID.

    \b
    Examples:
      htn ros node domains/domestic.jshop --problem problems/bring_object.jshop
      htn ros send '((bring_object jenny pringles guest))'
    """
    if find_spec("rclpy") is None:
        raise HtnError(f"htn ros {MISSING}")


@ros.command("node")
@click.argument("domain", type=click.Path(dir_okay=False))
@click.option(
    "--problem",
    type=click.Path(dir_okay=False),
    help="The world model's first state (its facts); default: empty.",
)
@click.option(
    "--robot",
    default="auto",
    show_default=True,
    help="The robot back end the goals run on: ros (the robot's action servers, "
    "named in the mapping file DOMAIN.ros.toml beside the domain), symbolic, "
    "pybullet, ...; auto: ros where that file exists, else symbolic.",
)
@click.option("--faults", default="", metavar="KIND=P,...", help="As htn run --faults.")
@click.option("--seed", type=int, default=0, show_default=True, help="As htn run --seed.")
@click.option("--replan", is_flag=True, help="As htn run --replan.")
@click.option(
    "--on-new-goal",
    type=click.Choice(["preempt", "reject", "queue"]),
    default="preempt",
    show_default=True,
    help="A goal that comes while one runs: preempt the running one (it halts at "
    "its current action; where the new goal's plan starts with that very "
    "action, the action goes on and the new goal takes it as done), reject the "
    "new one, or run it after.",
)
@click.option(
    "--resume",
    is_flag=True,
    help="A goal preempted by a newer goal (--on-new-goal preempt) does not end: "
    "it waits, and once the newer goal has ended (verified, refused or "
    "cancelled) its remaining top-level tasks are planned again from the world "
    "model and run (a task begun is planned whole, from where it stopped), the "
    "steps it verified staying done; its result is the whole goal's. If the "
    "newer goal fails or aborts, the waiting goals end preempted.",
)
@click.option(
    "--managed", is_flag=True, help="Leave configure and activate to a lifecycle manager."
)
@click.option(
    "--log-dir",
    type=click.Path(file_okay=False),
    help="Write each goal's run as htn run --log does (htn view shows it).",
)
@click.option(
    "--view",
    is_flag=True,
    help="Watch the goals in a browser (the view extra): prints the URL; each goal's "
    "run is shown as htn run --view shows one, the page moving on to the next goal.",
)
@click.option(
    "--view-port",
    type=click.IntRange(0, 65535),
    default=0,
    show_default=True,
    help="The view's port (0: a free one); it is served on 127.0.0.1.",
)
@click.option("--name", default="htn", show_default=True, help="The node's name.")
def node(
    domain,
    problem,
    robot,
    faults,
    seed,
    replan,
    on_new_goal,
    resume,
    managed,
    log_dir,
    view,
    view_port,
    name,
):
    """Serve goals for DOMAIN: the action ~/execute (plan from the world
    model, run with monitors, retries and repair, each event as feedback and
    on ~/events), the services ~/plan, ~/state and ~/update_facts, and the
    topic ~/facts. Ctrl-C stops it."""
    from .node import NodeSettings, serve

    settings = NodeSettings(
        domain,
        problem,
        robot,
        faults,
        seed,
        replan,
        on_new_goal,
        log_dir,
        resume,
        ("127.0.0.1", view_port) if view else None,
    )
    sys.exit(
        serve(
            settings,
            managed=managed,
            name=name,
            on_view=lambda url: click.echo(f"view: {url}", err=True),
        )
    )


@ros.command("send")
@click.argument("tasks", required=False)
@click.option(
    "--from-problem",
    type=click.Path(dir_okay=False),
    help="Send the task list of this problem file instead.",
)
@click.option(
    "--cancel-after",
    type=float,
    metavar="SECONDS",
    help="Cancel the goal after this long (it ends preempted).",
)
@click.option("--node", "node_name", default="htn", show_default=True, help="The node's name.")
@click.option("-q", "--quiet", is_flag=True, help="Print only the result's summary.")
def send(tasks, from_problem, cancel_after, node_name, quiet):
    """Send TASKS (a task list, e.g. '((bring_object jenny pringles guest))')
    to the node and print each event as htn run prints its steps, then the
    result's summary. Exit code 0 verified, 1 failed, aborted or preempted,
    2 refused (the located error is printed)."""
    from htn.api.run import event_line

    from .node import send_goal

    if (tasks is None) == (from_problem is None):
        raise click.UsageError("give TASKS or --from-problem FILE (one of them)")
    if from_problem:
        tasks = _tasks_of(from_problem)

    def show(rec):
        line = event_line(rec)
        if line is not None and not quiet:
            click.echo(line)

    result = send_goal(tasks, on_event=show, cancel_after=cancel_after, node_name=node_name)
    if result.outcome == "refused":
        raise _located(result.error)
    click.echo(result.summary)
    sys.exit(0 if result.outcome == "verified" else 1)


def _located(error: str) -> HtnError:
    """The node's located error (``goal:1:3: message``) as the command
    line prints its own."""
    m = re.match(
        r"(?P<file>[^:]+):(?:(?P<line>\d+):(?:(?P<col>\d+):)?)? (?P<message>.*)\Z", error, re.S
    )
    if m is None:
        return HtnError(error)
    line, col = m["line"], m["col"]
    return HtnError(m["message"], m["file"], int(line) if line else None, int(col) if col else None)


def _tasks_of(path: str) -> str:
    """The task list of a problem file's first instance, as source text."""
    from htn.jshop.language import syntax as S
    from htn.jshop.language.terms import source_atom
    from htn.jshop.readers.load import load_problem

    prob = load_problem(path)
    atoms = S.task_atoms(prob.instances[0].tasks)
    return "(" + " ".join(source_atom(t.name, t.args) for t in atoms) + ")"


from .robot_commands import robot  # noqa: E402  (the group above, its commands in their modules)

ros.add_command(robot)


from .record_commands import record  # noqa: E402

ros.add_command(record)
