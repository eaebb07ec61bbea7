"""The head camera: what the robot sees of a body, and where it believes it is.

An object counts as seen when it covers at least ``SEEN_PIXELS`` pixels of
the segmentation image of the head camera looking at a target; a detection
records its position with a few millimetres of noise. The ``detect`` fault
makes a look miss.
"""

from __future__ import annotations

import math

import numpy as np

from .base import MobileBase
from .faults import FaultDraws
from .interface import Check
from .physics import Physics

CAMERA_HEIGHT = 1.45
SEEN_PIXELS = 5


class Perception:
    """Looking with the head camera (``pixels``: width, height of its image),
    and the detections it leaves."""

    def __init__(
        self, physics: Physics, base: MobileBase, draws: FaultDraws, pixels: tuple[int, int]
    ):
        self.physics, self.base, self.draws = physics, base, draws
        self.pixels = pixels
        self.detections: dict[str, tuple] = {}  # object -> where it was seen

    def visible_pixels(self, name: str, target) -> int:
        """Pixels of ``name`` in the head camera's segmentation image, looking at ``target``."""
        p, c = self.physics.p, self.physics.cid
        x, y, yaw = self.base.pose
        w_, h_ = self.pixels
        eye = [x + 0.1 * math.cos(yaw), y + 0.1 * math.sin(yaw), CAMERA_HEIGHT]
        view = p.computeViewMatrix(eye, list(target), [0, 0, 1], physicsClientId=c)
        proj = p.computeProjectionMatrixFOV(70, 4 / 3, 0.1, 8.0, physicsClientId=c)
        img = p.getCameraImage(w_, h_, view, proj, renderer=p.ER_TINY_RENDERER, physicsClientId=c)
        seg = np.asarray(img[4]).reshape(h_, w_)
        return int(np.count_nonzero((seg & ((1 << 24) - 1)) == self.physics.body_of[name]))

    def noisy_pos(self, name: str) -> tuple:
        """Where perception puts a body: its position with a few millimetres of noise."""
        rng = self.draws.rng
        return tuple(
            self.physics.body_pos(name) + np.array([rng.gauss(0, 0.003), rng.gauss(0, 0.003), 0])
        )

    def look(self, obj: str, target) -> int:
        """Look at ``target`` for ``obj``; record a detection when it is seen.
        Returns the pixels (0 after a detection fault)."""
        pixels = self.visible_pixels(obj, target)
        if self.draws.happens("detect"):
            pixels = 0
            self.draws.inject("detect", f"{obj} missed")
        if pixels >= SEEN_PIXELS:
            self.detections[obj] = self.noisy_pos(obj)
        return pixels

    def check_detection(self, obj: str) -> Check:
        det = self.detections.get(obj)
        if det is None:
            return Check(False, f"no detection of {obj}")
        err = float(np.linalg.norm(np.array(det) - self.physics.body_pos(obj)))
        return Check(err < 0.03, f"detection {err:.3f} m from {obj}")
