"""What a run writes besides its log: the behaviour tree in DOT
(``bt_dot``) and a labelled camera snapshot per action attempt
(``snapshots``, a folder).

Every output is checked before any work starts (a folder that exists or
can be made, a file that can be written, none an input of the run nor
another of its outputs); the snapshot folder is made only once the robot
is built and has a camera, so a run refused earlier leaves no trace.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from htn.files import atomic_write, check_output_file, check_output_folder, make_output_folder
from htn.jshop.language.errors import HtnError
from htn.robot.interface import Robot

if TYPE_CHECKING:
    from py_trees.behaviour import Behaviour


@dataclass
class RunOutputs:
    """The paths a run writes (None: not written)."""

    log: str | None = None
    bt_dot: str | None = None
    snapshots: str | None = None

    def check(self, inputs: Iterable[object]) -> None:
        """Each can be written and none is an input (``inputs``: paths or
        None) or another output."""
        given = [
            (p, o)
            for p, o in (
                (self.log, "--log"),
                (self.bt_dot, "--bt-dot"),
                (self.snapshots, "--snapshots"),
            )
            if p
        ]
        paths = [i for i in inputs if isinstance(i, str)]
        for path, option in given:
            others = [x for x in given if x[1] != option]
            if option == "--snapshots":
                check_output_folder(path, option, paths, others)
            else:
                check_output_file(path, option, paths, others)

    def prepare_snapshots(self, robot: Robot, robot_name: str) -> None:
        """The snapshot folder, made once the robot is known to have a camera."""
        if not self.snapshots:
            return
        if type(robot).snapshot is Robot.snapshot:
            raise HtnError(f"--snapshots: the {robot_name} robot has no camera")
        make_output_folder(self.snapshots, "--snapshots")

    def snapshot_listener(self, robot: Robot) -> Callable[[dict[str, Any]], None] | None:
        """The event listener that saves the snapshots (None: none asked)."""
        if not self.snapshots:
            return None
        from htn.executor.snapshots import snapshot_listener

        return snapshot_listener(robot, self.snapshots)

    def write_dot(self, root: Behaviour) -> None:
        """py_trees' DOT export of the tree ``root``, with readable names."""
        if not self.bt_dot:
            return
        from htn.executor.bt_dot import behaviour_tree_dot

        with atomic_write(self.bt_dot, "--bt-dot") as fh:
            fh.write(behaviour_tree_dot(root))
