"""What both PyBullet robots are: a :class:`~htn.robot.interface.Robot`
holding its parts, each handed what it needs.

The parts are objects: the :class:`~htn.robot.physics.Physics` (the client,
its clock and the named bodies), the seeded :class:`~htn.robot.faults.FaultDraws`,
the :class:`~htn.robot.base.MobileBase`, the head camera's
:class:`~htn.robot.perception.Perception`, the
:class:`~htn.robot.camera.OverviewCamera`, and the arm or arms. A robot
builds its world and its parts in ``_build`` (the domestic robot,
:mod:`~htn.robot.pybullet_sim`; the kitchen robot, :mod:`~htn.robot.kitchen_sim`)
and offers the skills and checks the executor calls by name; those both
robots share are here, with the grasp's preamble.
"""

from __future__ import annotations

from .arm import Arm
from .base import MobileBase
from .camera import OverviewCamera
from .faults import FaultDraws, Faults
from .interface import Caption, Check, Robot, SkillResult, check, skill
from .odometry import Odometry
from .perception import Perception
from .physics import STEPS_PER_TICK, Physics, quiet_fds
from .world import World


class SimulatedRobot(Robot):
    """A PyBullet robot; ``gui=True`` opens a window (needs a display)."""

    steps_per_tick = STEPS_PER_TICK
    GRIP_TOLERANCE = 0.05  # m: a held object's centre this close to its gripper counts as grasped
    base: MobileBase  # the parts _build makes
    perception: Perception
    camera: OverviewCamera

    def __init__(
        self,
        world: World,
        gui: bool = False,
        faults: Faults | None = None,
        seed: int = 0,
        speech=None,
    ):
        self.world = world
        self.physics = Physics(gui)
        self.draws = FaultDraws(faults or Faults(), seed, lambda: self.physics.sim_time)
        self.spoken: list[str] = []
        self.speech = speech
        with quiet_fds():
            self._build()
        self.physics.name_bodies()
        self.odometry = Odometry(self.physics, self.base)  # distances from here on
        self.odometry.sample()
        self.physics.after_step.append(self.odometry.sample)

    def _build(self) -> None:  # pragma: no cover - each robot builds its own
        """The world's bodies and the robot's parts; the world settled."""
        raise NotImplementedError

    # ------------------------------------------------------------ what each robot says
    def _holding(self, obj: str) -> Arm | None:  # pragma: no cover
        """The arm whose gripper holds ``obj``, if any."""
        raise NotImplementedError

    def _carried_bodies(self) -> set:  # pragma: no cover
        """Bodies the robot carries: touching them is no collision."""
        raise NotImplementedError

    def detect_object(self, obj: str, where: str):  # pragma: no cover
        raise NotImplementedError

    def _move_object_elsewhere(self, obj: str, where: str):  # pragma: no cover
        """The ``moved`` fault: somebody takes ``obj`` from ``where`` elsewhere."""
        raise NotImplementedError

    # ------------------------------------------------------------ skills
    def _grasp_target(self, obj: str, where: str, area: str):
        """What every grasp does first: where ``obj`` was detected, looking at
        ``where`` again without a detection (e.g. on a retry); None if it is
        not seen. With a detection, the ``moved`` fault may take the object
        from ``area`` to another table just before the grasp (the robot then
        grasps where it saw it)."""
        if obj not in self.perception.detections:
            yield from self.detect_object(obj, where)
        guess = self.perception.detections.get(obj)
        if guess is not None and self.draws.moved_once(obj):
            yield from self._move_object_elsewhere(obj, area)
        return guess

    @skill("say")
    def say(self, message: str):
        text = message.replace("_", " ")
        self.spoken.append(message)
        if self.speech is not None:
            self.speech(text)
        yield from self.physics.settle(0.05 * len(text))  # speaking takes time
        return SkillResult(True, f'said "{text}"')

    def hold(self) -> None:
        self.physics.run(self.physics.step(12))

    # ------------------------------------------------------------ checks (monitors)
    @check("base_at")
    def check_base_at(self, place: str) -> Check:
        return self.base.check_at(place)

    @check("no_collision")
    def check_no_collision(self) -> Check:
        hits = self.base.contacts(self._carried_bodies())
        return Check(not hits, "touching " + ", ".join(hits) if hits else "no contact")

    @check("in_gripper")
    def check_in_gripper(self, obj: str) -> Check:
        """The effect of a grasp: the object is held up by the gripper holding
        it: close to it, above every table top, and attached."""
        if obj not in self.physics.body_of:
            return Check(False, f"no object {obj}")
        arm = self._holding(obj)
        if arm is None:
            return Check(False, f"{obj} is in no gripper")
        return arm.holds_up(obj, self.GRIP_TOLERANCE)

    @check("still_held")
    def check_still_held(self, obj: str) -> Check:
        """While the robot carries ``obj``: still attached to its gripper and near it."""
        arm = self._holding(obj) if obj in self.physics.body_of else None
        if arm is None:
            return Check(False, f"{obj} is in no gripper")
        return arm.still_holds(obj)

    @check("detection")
    def check_detection(self, obj: str) -> Check:
        return self.perception.check_detection(obj)

    @check("said")
    def check_said(self, message: str) -> Check:
        ok = bool(self.spoken) and self.spoken[-1] == message
        return Check(ok, "spoken" if ok else "not spoken")

    # ------------------------------------------------------------ the robot as a whole
    @property
    def sim_time(self) -> float:
        return self.physics.sim_time

    @sim_time.setter
    def sim_time(self, value: float) -> None:  # Robot.sim_time is writeable
        self.physics.sim_time = value

    @property
    def injected(self) -> list[dict]:
        return self.draws.injected

    def inject(self, kind: str, detail: str) -> None:
        self.draws.inject(kind, detail)

    def snapshot(self, path: str, label: Caption | None = None) -> str | None:
        return self.camera.snapshot(path, label)

    def camera_frame(self, width: int = 320, height: int = 240) -> bytes | None:
        return self.camera.camera_frame(width, height)

    def close(self) -> None:
        self.physics.close()

    # ------------------------------------------------------------ read by the tests' oracle
    # (tests/monitoring_oracle.py reads the simulation itself through these)
    @property
    def p(self):
        return self.physics.p

    @property
    def cid(self) -> int:
        return self.physics.cid

    @property
    def plane(self) -> int | None:
        return self.physics.plane

    @property
    def body_of(self) -> dict[str, int]:
        return self.physics.body_of

    @property
    def furniture_top(self) -> dict[str, float]:
        return self.physics.furniture_top

    @property
    def husky(self) -> int:
        return self.base.body

    @property
    def arm_body(self) -> dict[str, int]:  # pragma: no cover - each robot has its arms
        """The arms' bodies by name."""
        raise NotImplementedError

    @property
    def detections(self) -> dict[str, tuple]:
        return self.perception.detections

    def _mounted(self) -> list[tuple[int, list[float]]]:
        return self.base.mounted()
