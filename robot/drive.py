"""The base's motion controller: velocity commands under acceleration limits,
and a goal tolerance; a motion ends where the controller leaves the base.

A real base does not stop exactly on its goal: its controller commands
velocities, the wheels follow them only as fast as their acceleration
allows, and the controller stops commanding once the base is within its goal
tolerance (ROS's ``xy_goal_tolerance``, ``yaw_goal_tolerance``). Both
simulated robots move their base this way, one physics step at a time:

- a turn in place: the angular velocity follows a trapezoidal profile (up to
  the turning speed, braking so as to arrive, never slower than
  :data:`MIN_TURN`) until the heading is within :data:`YAW_TOL`; then the
  command is zero and the base brakes to rest;
- a straight drive: the same profile on the distance still to go along the
  heading, forwards or backwards (as the goal lies at the start), while the
  heading is steered towards the goal point (held in the last
  :data:`HOLD_HEADING` metres, where the bearing is ill-defined); it stops
  commanding within :data:`XY_TOL` of the goal, or once it has passed it.

The residual error is therefore real and measured (the monitors read the
base's pose from PyBullet): a few millimetres and milliradians, different for
each motion. The base itself is kinematic (placed at each step, as the arm
is): collisions do not stop it, the ``no collision`` hold-monitor does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

XY_TOL = 0.01  # m: the drive stops commanding this close to its goal
YAW_TOL = 0.01  # rad: a turn stops commanding this close to its heading
MIN_SPEED = 0.04  # m/s: the slowest the wheels run smoothly
MIN_TURN = 0.08  # rad/s
HOLD_HEADING = 0.1  # m: no steering this close to the goal
HEADING_GAIN = 2.0  # 1/s: steering rate per radian of bearing error
BRAKING = 0.8  # profiles brake at this share of the acceleration limit
REST = 1e-4  # m/s, rad/s: at rest
MAX_SECONDS = 60.0  # a motion that has not ended by then is cut (never seen)


@dataclass(frozen=True)
class Limits:
    """The base's speed and acceleration limits."""

    speed: float  # m/s
    turn: float  # rad/s
    accel: float  # m/s^2
    turn_accel: float  # rad/s^2


def angle_diff(a: float, b: float) -> float:
    return (a - b + math.pi) % (2 * math.pi) - math.pi


def follow(current: float, command: float, accel: float, dt: float) -> float:
    """The velocity one step later: towards ``command``, at most ``accel * dt`` away."""
    step = accel * dt
    return current + max(-step, min(step, command - current))


def profile(remaining: float, top: float, floor: float, accel: float) -> float:
    """Speed commanded with ``remaining`` to go: as fast as braking at
    ``BRAKING * accel`` still arrives, between ``floor`` and ``top``."""
    return max(floor, min(top, math.sqrt(2 * BRAKING * accel * max(remaining, 0.0))))


def turn_steps(yaw: float, goal: float, lim: Limits, dt: float):
    """Headings of a turn in place from ``yaw`` to ``goal``, one per step."""
    w, stopping = 0.0, False
    for _ in range(int(MAX_SECONDS / dt)):
        err = angle_diff(goal, yaw)
        stopping = stopping or abs(err) < YAW_TOL
        command = (
            0.0
            if stopping
            else math.copysign(profile(abs(err), lim.turn, MIN_TURN, lim.turn_accel), err)
        )
        w = follow(w, command, lim.turn_accel, dt)
        if stopping and abs(w) < REST:
            return
        yaw += w * dt
        yield yaw


def drive_steps(pose: tuple, goal: tuple, lim: Limits, dt: float):
    """Poses ``(x, y, yaw, travelled)`` of a drive from ``pose`` to the point
    ``goal``, one per step."""
    x, y, yaw = pose
    gx, gy = goal
    bearing = angle_diff(math.atan2(gy - y, gx - x), yaw)
    direction = 1.0 if math.cos(bearing) >= 0 else -1.0
    v = w = travelled = 0.0
    stopping = False
    for _ in range(int(MAX_SECONDS / dt)):
        dx, dy = gx - x, gy - y
        rho = math.hypot(dx, dy)
        bearing = angle_diff(math.atan2(dy, dx), yaw)
        along = rho * math.cos(bearing) * direction  # still to go, along the heading
        stopping = stopping or rho < XY_TOL or along <= 0.0
        if stopping:
            v_cmd = w_cmd = 0.0
        else:
            v_cmd = direction * profile(along, lim.speed, MIN_SPEED, lim.accel)
            off = bearing if direction > 0 else angle_diff(bearing, math.pi)
            w_cmd = 0.0 if rho < HOLD_HEADING else max(-lim.turn, min(lim.turn, HEADING_GAIN * off))
        v = follow(v, v_cmd, lim.accel, dt)
        w = follow(w, w_cmd, lim.turn_accel, dt)
        if stopping and abs(v) < REST and abs(w) < REST:
            return
        x += v * math.cos(yaw) * dt
        y += v * math.sin(yaw) * dt
        yaw += w * dt
        travelled += abs(v) * dt
        yield x, y, yaw, travelled
