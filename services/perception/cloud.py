"""Check an incoming ``sim/cloud`` message and expose its points without copying them.

Why a separate step: every later stage may assume a well-formed organised
cloud, and every way a cloud can be unusable gets one specific, human-readable
reason (published as the perception status) instead of an exception deep
inside the pipeline. Why no copy: a 640x480 cloud has 300 000 points and only
a few percent of them are objects; later stages pick what they need by pixel
index (the heights of NaN or infinite points fail every comparison).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from shared.messages import Cloud as CloudMessage


class CloudError(ValueError):
    """The cloud cannot be used; the message says why, in words for the user."""


@dataclass(frozen=True)
class Cloud:
    """An organised cloud flattened to pixels: row-major, NaN where there was no return."""

    xyz: np.ndarray  # (H*W, 3) float32, base frame
    rgb: np.ndarray  # (H*W, 3) uint8
    valid: np.ndarray  # (M,) pixel indices of the finite points
    shape: tuple[int, int]  # (H, W): neighbours in the image


MIN_POINTS = 500


def cloud_from_message(message: CloudMessage) -> Cloud:
    """The cloud of ``message``; raise :class:`CloudError` naming what is wrong with it."""
    xyz, rgb = message.xyz, message.rgb
    if xyz.ndim != 3 or xyz.shape[-1] != 3:
        raise CloudError(f"cloud xyz must have shape (H, W, 3), got {xyz.shape}")
    if rgb.shape != xyz.shape:
        raise CloudError(f"cloud rgb shape {rgb.shape} does not match xyz shape {xyz.shape}")
    if xyz.dtype.kind != "f":
        raise CloudError(f"cloud xyz must be floating point, got {xyz.dtype}")
    flat = xyz.reshape(-1, 3).astype(np.float32, copy=False)
    with np.errstate(invalid="ignore", over="ignore"):
        valid = np.flatnonzero(np.isfinite(flat.sum(axis=1)))  # NaN or inf anywhere poisons the sum
    if len(valid) < MIN_POINTS:
        raise CloudError(f"point cloud is empty ({len(valid)} valid points of {len(flat)})")
    return Cloud(flat, rgb.reshape(-1, 3).astype(np.uint8, copy=False), valid, (xyz.shape[0], xyz.shape[1]))


def camera_position(message: CloudMessage) -> np.ndarray:
    """Where the camera was (``camera_pose``'s x, y, z); raise :class:`CloudError` when it is not finite."""
    pose = np.asarray(message.camera_pose, dtype=float)
    if not np.isfinite(pose).all():
        raise CloudError("camera_pose must be 7 finite numbers [x, y, z, qw, qx, qy, qz]")
    return pose[:3]
