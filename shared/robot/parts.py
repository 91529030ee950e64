"""The pieces a robot description is made of: named postures, the gripper, the head camera.

Why separate from any one robot: the services read these fields by name
(``robot.gripper.state(...)``, ``robot.camera.intrinsics(...)``) and must not
care which robot fills them in, so a second description fits the same shapes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from shared.contract import GripperState


@dataclass(frozen=True)
class Keyframe:
    """A named posture: joint name -> position, and where the head looks (base frame), if it says."""

    joints: dict[str, float]
    gaze: tuple[float, float, float] | None = None


@dataclass(frozen=True)
class GripperSpec:
    """One parallel gripper: its opening range, the usual commands and how its read-back is judged.

    A gripper controller reports only how far the fingers are apart and how
    hard its motor pushes them together. ``state`` turns that pair into the
    words the rest of the system uses: fingers that met are ``closed``;
    fingers held apart while the motor still squeezes have something between
    them (``holding``); otherwise the hand is ``open``.
    """

    max_opening: float  # m between the pads, fully open
    open_width: float  # m, what "open" commands
    closed_below: float  # m: an opening under this means the pads met
    hold_effort: float  # N: squeezing at least this hard, fingers apart, holds something
    default_effort: float  # N per pad, the usual grip
    effort_range: tuple[float, float]  # N per pad a grip may ask for

    def state(self, opening: float, effort: float) -> GripperState:
        """``open`` / ``closed`` / ``holding`` from the measured ``opening`` (m) and squeezing ``effort`` (N)."""
        if opening < self.closed_below:
            return "closed"
        return "holding" if effort >= self.hold_effort else "open"


@dataclass(frozen=True)
class CameraSpec:
    """The head camera as the robot mounts it: frames, field of view, range and native resolution."""

    link: str  # x forward, y left, z up (how SAPIEN cameras look)
    optical_frame: str  # z forward, x right, y down
    horizontal_fov: float  # rad
    near: float  # m: nearer than this returns nothing
    far: float  # m: farther than this returns nothing
    width: int = 640
    height: int = 480

    def intrinsics(self, width: int | None = None, height: int | None = None) -> tuple[float, float, float, float]:
        """Pinhole ``fx, fy, cx, cy`` in pixels at ``width`` × ``height`` (square pixels, centred axis)."""
        width = self.width if width is None else width
        height = self.height if height is None else height
        focal = (width / 2) / math.tan(self.horizontal_fov / 2)
        return focal, focal, width / 2, height / 2

    def vertical_fov(self, width: int | None = None, height: int | None = None) -> float:
        """Vertical field of view (rad) at that resolution, with the horizontal one fixed."""
        fx, _, _, cy = self.intrinsics(width, height)
        return 2 * math.atan(cy / fx)
