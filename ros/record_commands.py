"""``htn ros record``: an htn node's topics into a rosbag2 bag (:mod:`htn.ros.record`),
which ``htn view BAG`` shows as it shows a log. The command parses, calls
the recorder (imported when it runs: ``htn ros --help`` imports no rclpy)
and prints."""

from __future__ import annotations

import math
import re

import click

NODE_NAME = re.compile(r"/?[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*")


def _seconds(ctx, param, value):
    """``--duration``: a positive, finite number of seconds."""
    if value is None:
        return None
    text = str(value).strip()
    try:
        seconds = float(text)
    except ValueError:
        raise click.BadParameter(
            f"{text[:40]!r} is not a number of seconds (e.g. 10 or 0.5)"
        ) from None
    if not math.isfinite(seconds) or seconds <= 0:
        raise click.BadParameter(f"{text[:40]!r}: give a positive number of seconds")
    return seconds


def _node_name(ctx, param, value):
    """``--node``: a ROS name (``htn``, ``robot1/htn``), its topics ``/NAME/...``."""
    if not NODE_NAME.fullmatch(value):
        raise click.BadParameter(
            f"{value[:40]!r} is not a ROS node name (letters, digits "
            "and _, not starting with a digit; / between namespaces)"
        )
    return value.strip("/")


@click.command("record")
@click.argument("output", type=click.Path())
@click.option(
    "--node",
    "node_name",
    default="htn",
    show_default=True,
    callback=_node_name,
    help="The node's name: its topics /NODE/events and /NODE/facts are recorded.",
)
@click.option(
    "--duration",
    callback=_seconds,
    metavar="SECONDS",
    help="Stop after this long (default: at Ctrl-C or SIGTERM).",
)
def record(output, node_name, duration):
    """Record the node's events (every executor event of every goal, as
    htn run --log writes them) and the facts others send it into a new
    rosbag2 bag OUTPUT (a folder; sqlite3 storage, which ros2 bag reads
    too), until Ctrl-C, SIGTERM or --duration; then print how many messages
    were recorded. An OUTPUT that exists is refused. htn view OUTPUT shows a
    recorded goal as it shows a log (--goal N: which one).

    \b
    Examples:
      htn ros record session                  # Ctrl-C stops it
      htn ros send '((bring_object jenny pringles guest))'   # in another shell
      htn view session
    """
    from htn.process import Stops

    from .record import record as record_bag

    stops = click.get_current_context().ensure_object(Stops)
    recording = record_bag(
        output,
        node_name,
        duration,
        held=stops.held,
        say=lambda line: click.echo(f"record: {line}", err=True),
    )
    stops.consume()  # Ctrl-C or SIGTERM is how a recording ends: exit 0
    click.echo(recording.line())
