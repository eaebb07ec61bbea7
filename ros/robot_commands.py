"""``htn ros robot``: a robot as ROS 2 action servers (the ``ros`` and ``sim``
extras); parses, calls :mod:`htn.ros.servers` and prints."""

from __future__ import annotations

import sys

import click


@click.command("robot")
@click.option(
    "--sim",
    is_flag=True,
    help="Serve the PyBullet robot (needed: a real robot serves these names itself).",
)
@click.option(
    "--problem",
    type=click.Path(dir_okay=False),
    help="The problem whose initial state is the world (default: the bundled "
    "bring_object problem; a kitchen problem gives the kitchen robot).",
)
@click.option("--faults", default="", metavar="KIND=P,...", help="As htn run --faults.")
@click.option("--seed", type=int, default=0, show_default=True, help="As htn run --seed.")
@click.option(
    "--speed",
    type=click.FloatRange(0, 1000),
    default=1.0,
    show_default=True,
    help="Simulated seconds per wall-clock second; 0: as fast as it can.",
)
@click.option(
    "--namespace",
    default="/robot",
    show_default=True,
    help="Where the skills, checks and topics are served (see the mapping file).",
)
@click.option("--gui", is_flag=True, help="Open PyBullet's window (needs a display).")
@click.option("--name", default="htn_robot_sim", show_default=True, help="The node's name.")
def robot(sim, problem, faults, seed, speed, namespace, gui, name):
    """Serve a robot over ROS 2: each skill the action NAMESPACE/skill/NAME
    (htn_interfaces/action/Skill) and driving also Nav2's /navigate_to_pose
    (nav2_msgs/action/NavigateToPose), each check the service
    NAMESPACE/check/NAME, what it observes NAMESPACE/observe, its pose
    NAMESPACE/pose (stamped with the simulated clock), the faults it injects
    NAMESPACE/faults. htn ros node (or htn run --robot ros) drives it through
    the mapping file beside the domain. Ctrl-C stops it.

    \b
    Example (three shells):
      htn ros robot --sim
      htn ros node domains/domestic.jshop --problem problems/bring_object.jshop
      htn ros send --from-problem problems/bring_object.jshop
    """
    from htn.api.extras import require_robot_extra

    if not sim:
        raise click.UsageError(
            "only the simulated robot is served here: give --sim (a real "
            "robot's own nodes serve the names of its mapping file)"
        )
    if not namespace.startswith("/") or namespace == "/":
        raise click.BadParameter("an absolute name such as /robot", param_hint="--namespace")
    require_robot_extra("pybullet", "htn ros robot --sim")
    from .servers import RobotSettings, serve

    def ready(node):
        click.echo(
            f"serving {len(node.skill_servers)} actions and {len(node.check_services)} services "
            f"under {namespace} (speed {speed:g}x); Ctrl-C stops",
            err=True,
        )

    sys.exit(
        serve(RobotSettings(problem, faults, seed, speed, namespace, gui), name, on_ready=ready)
    )
