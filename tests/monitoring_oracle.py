"""An oracle for monitored runs: does the simulator itself show that what an
``aborted`` event says is missing is really missing?

It reads PyBullet directly (body poses, link states, contact points), not
the robot's checks, at the moment each event is emitted:

* a monitor's ``aborted`` is explained when some effect the step's operator
  adds (JSHOP2 semantics, from the domain) is absent in the simulation;
* a hold-monitor's ``aborted`` (the event names the ``hold``) is explained
  when its condition is broken: the base or an arm touches something, or an
  object held at the start of the action is no longer at a gripper.

Used by ``tests/robot/test_monitoring.py`` and ``benchmarks/bench_recovery.py``.
"""

from __future__ import annotations

import math
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
EE_LINK = 11
POSE_TOLERANCE, YAW_TOLERANCE = 0.05, 0.05


class Oracle:
    """Listens to a run's events and judges every ``aborted`` one."""

    def __init__(self, robot, domain, instance):
        from htn.jshop.language import syntax as S
        from htn.jshop.search.planner import Planner

        self.robot, self.p, self.c = robot, robot.p, robot.cid
        self.domain, self.instance = domain, instance
        self.model = Planner(domain, S.ProblemInstance(instance.state, S.TaskList([])))
        self.held_at_start: list = []
        self.aborts = 0
        self.unexplained: list[str] = []
        self.fault_to_abort: list[tuple] = []  # (kind, fault sim_t, detail, abort sim_t, action)
        self._last_fault = None

    # ------------------------------------------------------------ simulator truth
    def _arms(self):
        bodies = getattr(self.robot, "arm_body", None)
        return list(bodies.values()) if bodies else [self.robot.arm]

    def _grippers(self):
        return [self.p.getLinkState(b, EE_LINK, physicsClientId=self.c)[4] for b in self._arms()]

    def _attached(self, obj):
        """Is a constraint holding ``obj`` to an arm (the simulator's grasp)?"""
        p, c, body, arms = self.p, self.c, self.robot.body_of[obj], set(self._arms())
        for i in range(p.getNumConstraints(physicsClientId=c)):
            info = p.getConstraintInfo(
                p.getConstraintUniqueId(i, physicsClientId=c), physicsClientId=c
            )
            if info[0] in arms and info[2] == body:
                return True
        return False

    def _pos(self, name):
        return self.p.getBasePositionAndOrientation(
            self.robot.body_of[name], physicsClientId=self.c
        )[0]

    def _at_gripper(self, obj, within):
        o = self._pos(obj)
        return any(math.dist(o, g) < within for g in self._grippers())

    def _lifted(self, obj):
        return self._pos(obj)[2] > max(self.robot.furniture_top.values()) + 0.1

    def _on(self, obj, furniture):
        top = self.robot.furniture_top[furniture]
        return any(
            cp[5][2] >= top - 0.02
            for cp in self.p.getContactPoints(
                bodyA=self.robot.body_of[obj],
                bodyB=self.robot.body_of[furniture],
                physicsClientId=self.c,
            )
        ) and not self._at_gripper(obj, 0.06)

    def _base_at(self, place):
        pl = self.robot.world.places[place]
        (x, y, _), orn = self.p.getBasePositionAndOrientation(
            self.robot.husky, physicsClientId=self.c
        )
        yaw = self.p.getEulerFromQuaternion(orn)[2]
        dyaw = abs((pl.theta - yaw + math.pi) % (2 * math.pi) - math.pi)
        return math.hypot(pl.x - x, pl.y - y) <= POSE_TOLERANCE and dyaw <= YAW_TOLERANCE

    def _detected(self, obj):
        det = self.robot.detections.get(obj)
        believed = getattr(self.robot, "believed_in", {}).get(obj)
        if believed is not None:
            return self.robot._in_drawer(obj, self.robot.drawers[believed])
        return det is not None and math.dist(det, self._pos(obj)) < 0.03

    def _touching(self):
        own = {self.robot.plane, self.robot.husky, *(b for b, _ in self.robot._mounted())}
        own |= self.robot._carried_bodies()
        mine = [self.robot.husky, *(b for b, _ in self.robot._mounted())]
        return any(
            cp[2] not in own
            for b in mine
            for cp in self.p.getContactPoints(bodyA=b, physicsClientId=self.c)
        )

    def holds(self, pred, args) -> bool:
        """Does the simulation show the atom ``(pred args...)``?"""
        if pred in ("robot_at", "robot-at"):
            return self._base_at(args[-1])
        if pred == "holding":
            obj = args[-1]
            return self._attached(obj) and self._at_gripper(obj, 0.06) and self._lifted(obj)
        if pred in ("object_on", "at"):
            obj, where = args
            return where in self.robot.furniture_top and self._on(obj, where)
        if pred in ("detected", "found"):
            obj = args[0]
            if obj in getattr(self.robot, "seen_persons", {}) or obj in self.robot.world.persons:
                return obj in self.robot.seen_persons
            return obj in self.robot.body_of and self._detected(obj)
        if pred == "has":
            return args[1] in self.robot._person_constraints
        if pred == "opened":
            return self.robot._is_open(self.robot.drawers[args[0]])
        return True  # free hands, trays, ...: not what the monitors here judge

    # ------------------------------------------------------------ events
    def event(self, rec) -> None:
        if rec["event"] == "fault":
            self._last_fault = (rec["kind"], rec["sim_t"], rec["detail"])
        if rec["event"] == "start":
            self.held_at_start = [
                o for o in self.robot.world.things if o in self.robot.body_of and self._attached(o)
            ]
        if rec["event"] != "aborted":
            return
        self.aborts += 1
        if self._last_fault is not None:
            self.fault_to_abort.append((*self._last_fault, rec["sim_t"], rec["action"]))
            self._last_fault = None
        if self._explained(rec):
            return
        self.unexplained.append(f"{rec['action']} at {rec['sim_t']} s: {rec['detail']}")

    def _explained(self, rec) -> bool:
        hold = rec.get("hold")
        if hold == "no collision":
            return self._touching()
        if hold is not None:
            return any(
                not (self._attached(o) and self._at_gripper(o, 0.15)) for o in self.held_at_start
            )
        from htn.jshop.readers.jshop2 import parse_step

        step = parse_step(rec["action"], "<log>", 1)
        added = set()
        for op, env in self.model.step_options(step.name, tuple(step.args)):
            added |= set(self.model.effects(op, env)[1])
        return any(not self.holds(p, a) for p, a in added)

    def verified(self, rec) -> None:
        """Keep the operator model in step with the verified effects (and,
        after a repair, with what was observed, as the dispatcher does)."""
        if rec["event"] == "replanned":
            from htn.executor.repair import observed_instance
            from htn.jshop.language import syntax as S
            from htn.jshop.search.planner import Planner

            seen = observed_instance(self.domain, self.instance, self.robot)
            self.model = Planner(self.domain, S.ProblemInstance(seen.state, S.TaskList([])))
        if rec["event"] == "verified":
            from htn.jshop.readers.jshop2 import parse_step

            step = parse_step(rec["action"], "<log>", 1)
            self.model.apply_step(step.name, tuple(step.args))


_LOADED: dict = {}


def _load(problem_file: str):
    """Domain, problem instance and domain path of a problem (parsed once per process)."""
    if problem_file not in _LOADED:
        from htn.jshop import load_domain, load_problem
        from htn.robot.world import is_kitchen_state

        inst = load_problem(problem_file).instances[0]
        domain = str(
            ROOT
            / "domains"
            / ("kitchen.jshop" if is_kitchen_state(inst.state) else "domestic.jshop")
        )
        _LOADED[problem_file] = (load_domain(domain), inst, domain)
    return _LOADED[problem_file]


def run_checked(
    problem: str, faults: str, seed: int, replan: bool, steps=None, problem_file=None
) -> dict:
    """One monitored run in PyBullet with the oracle listening."""
    from htn.executor.config import load_retries
    from htn.executor.dispatcher import TaskDispatcher
    from htn.executor.log import EventLog
    from htn.jshop import Planner
    from htn.robot import simulated_robot
    from htn.robot.faults import Faults

    dom, inst, domain = _load(str(problem_file or ROOT / "problems" / f"{problem}.jshop"))
    tree = None
    if steps is None:
        plan = next(Planner(dom, inst, record_trees=True).plans())
        steps, tree = plan.steps, plan.tree
    robot = simulated_robot(inst.state, faults=Faults.parse(faults), seed=seed)
    try:
        log = EventLog(None, clock=lambda: robot.sim_time)
        oracle = Oracle(robot, dom, inst)
        log.listeners += [oracle.event, oracle.verified]
        summary = TaskDispatcher(
            robot, dom, inst, steps, load_retries(domain), log, replan=replan, tree=tree
        ).run()
        return {
            "seed": seed,
            "result": summary.result,
            "aborts": oracle.aborts,
            "false_alarms": oracle.unexplained,
            "faults": len(robot.injected),
            "kinds": sorted({f["kind"] for f in robot.injected}),
            "fault_to_abort": oracle.fault_to_abort,
            "repaired": [e["path"] for e in log.events if e["event"] == "replanned"],
            "sim_time": summary.sim_time,
            "summary": summary,
        }
    finally:
        robot.close()
