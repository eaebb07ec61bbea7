"""The overview camera of the PyBullet robots: a view of the world from behind
and above the robot, following it.

:meth:`OverviewCamera.snapshot` saves it as a labelled PNG (``htn run
--snapshots``): a caption band along the bottom says what the picture shows,
the step and its action, the attempt, its outcome (coloured: verified green,
aborted or failed red) and the simulated time, then the monitor's detail, so
an aborted attempt and a verified one no longer look alike.
:meth:`OverviewCamera.camera_frame` renders it into memory as a JPEG (the
browser view of ``htn run --view``). Both render with PyBullet's CPU
renderer (no display needed) in the thread that owns the simulation: call
them between two ticks, never from another thread.
"""

from __future__ import annotations

import io
import math

import numpy as np

from .base import MobileBase
from .interface import Caption
from .physics import Physics

SIZE = (800, 600)  # width, height of a snapshot (pixels)
BAND = (20, 24, 28, 200)  # the caption band's colour, a little transparent
TONE = {
    "verified": (120, 220, 120),
    "finished": (230, 230, 230),
    "aborted": (255, 110, 100),
    "failed": (255, 110, 100),
}
TEXT = (240, 240, 240)
FONT_SIZE = 17


class OverviewCamera:
    """The camera that follows ``base``, looking from behind and above it."""

    def __init__(self, physics: Physics, base: MobileBase):
        self.physics, self.base = physics, base

    def _overview_rgb(self, width: int, height: int) -> np.ndarray:
        p, c = self.physics.p, self.physics.cid
        x, y, yaw = self.base.pose
        eye = [x - 2.2 * math.cos(yaw) + 0.8, y - 2.2 * math.sin(yaw) - 0.8, 2.6]
        view = p.computeViewMatrix(
            eye,
            [x + 0.6 * math.cos(yaw), y + 0.6 * math.sin(yaw), 0.5],
            [0, 0, 1],
            physicsClientId=c,
        )
        proj = p.computeProjectionMatrixFOV(60, width / height, 0.1, 20, physicsClientId=c)
        w_, h_, rgb, _, _ = p.getCameraImage(
            width, height, view, proj, renderer=p.ER_TINY_RENDERER, physicsClientId=c
        )
        return np.asarray(rgb, dtype=np.uint8).reshape(h_, w_, 4)[:, :, :3]

    def snapshot(self, path: str, label: Caption | None = None) -> str | None:
        """Save a PNG (:data:`SIZE`) from the overview camera, with ``label`` drawn on it."""
        from PIL import Image

        image = Image.fromarray(self._overview_rgb(*SIZE))
        if label is not None:
            image = _captioned(image, label)
        image.save(path)
        return path

    def camera_frame(self, width: int = 320, height: int = 240) -> bytes | None:
        """The overview camera's image now, as JPEG bytes."""
        from PIL import Image

        out = io.BytesIO()
        Image.fromarray(self._overview_rgb(width, height)).save(out, "JPEG", quality=80)
        return out.getvalue()


def _font(size: int):
    from PIL import ImageFont

    try:
        return ImageFont.load_default(size=size)  # Pillow >= 10.1: scalable
    except TypeError:  # older Pillow: its bitmap font
        return ImageFont.load_default()


def _captioned(image, label: Caption):
    """``image`` with the caption band drawn along its bottom."""
    from PIL import Image, ImageDraw

    font = _font(FONT_SIZE)
    lines = label.lines()
    width = image.width - 24
    lines = [lines[0], lines[1], *(_wrap(lines[2], font, width)[:2] if len(lines) > 2 else [])]
    step = FONT_SIZE + 7
    top = image.height - step * len(lines) - 14
    band = Image.new("RGBA", image.size, (0, 0, 0, 0))
    draw = ImageDraw.Draw(band)
    draw.rectangle([0, top, image.width, image.height], fill=BAND)
    for k, text in enumerate(lines):
        colour = TONE.get(label.outcome, TEXT) if k == 1 else TEXT
        draw.text((12, top + 7 + k * step), text, font=font, fill=colour)
    return Image.alpha_composite(image.convert("RGBA"), band).convert("RGB")


def _wrap(text: str, font, width: int) -> list[str]:
    """``text`` in lines no wider than ``width`` pixels."""
    words, lines, line = text.split(), [], ""
    for word in words:
        trial = f"{line} {word}".strip()
        if line and font.getlength(trial) > width:
            lines.append(line)
            line = word
        else:
            line = trial
    return lines + ([line] if line else [])
