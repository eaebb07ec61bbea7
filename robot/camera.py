"""The overview camera of the PyBullet robots: a view of the world from behind
and above the robot, following it.

:meth:`OverviewCamera.snapshot` saves it as a PNG (``htn run --snapshots``);
:meth:`OverviewCamera.camera_frame` renders it into memory as a JPEG (the
browser view of ``htn run --view``). Both render with PyBullet's CPU
renderer in the thread that owns the simulation: call them between two
ticks, never from another thread.
"""
from __future__ import annotations

import io
import math
from typing import Optional

import numpy as np


class OverviewCamera:
    """A part of a PyBullet robot (needs ``p``, ``cid`` and ``base``)."""

    def _overview_rgb(self, width: int, height: int) -> np.ndarray:
        p, c = self.p, self.cid
        x, y, yaw = self.base
        eye = [x - 2.2 * math.cos(yaw) + 0.8, y - 2.2 * math.sin(yaw) - 0.8, 2.6]
        view = p.computeViewMatrix(eye, [x + 0.6 * math.cos(yaw), y + 0.6 * math.sin(yaw), 0.5],
                                   [0, 0, 1], physicsClientId=c)
        proj = p.computeProjectionMatrixFOV(60, width / height, 0.1, 20, physicsClientId=c)
        w_, h_, rgb, _, _ = p.getCameraImage(width, height, view, proj,
                                             renderer=p.ER_TINY_RENDERER, physicsClientId=c)
        return np.asarray(rgb, dtype=np.uint8).reshape(h_, w_, 4)[:, :, :3]

    def snapshot(self, path: str) -> Optional[str]:
        """Save a PNG (480 x 360) from the overview camera."""
        from PIL import Image
        Image.fromarray(self._overview_rgb(480, 360)).save(path)
        return path

    def camera_frame(self, width: int = 320, height: int = 240) -> Optional[bytes]:
        """The overview camera's image now, as JPEG bytes."""
        from PIL import Image
        out = io.BytesIO()
        Image.fromarray(self._overview_rgb(width, height)).save(out, "JPEG", quality=80)
        return out.getvalue()
