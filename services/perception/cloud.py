"""Check an incoming ``sim/cloud`` message and turn it into valid points.

Why a separate step: every later stage may assume finite float points with
matching colours, and every way a cloud can be unusable gets one specific,
human-readable reason (published as the perception status) instead of an
exception deep inside the pipeline.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np


class CloudError(ValueError):
    """The cloud cannot be used; the message says why, in words for the user."""


@dataclass(frozen=True)
class Points:
    """The finite returns of one organised cloud, flattened."""

    xyz: np.ndarray  # (N, 3) float32, base frame
    rgb: np.ndarray  # (N, 3) uint8
    pixels: int      # H * W of the organised cloud, for resolution-aware thresholds


MIN_POINTS = 500


def points_from_message(message: dict[str, Any]) -> Points:
    """The finite points of ``message``; raise :class:`CloudError` naming what is wrong."""
    xyz, rgb = message.get("xyz"), message.get("rgb")
    if not isinstance(xyz, np.ndarray) or not isinstance(rgb, np.ndarray):
        raise CloudError("cloud message lacks xyz or rgb arrays")
    if xyz.ndim != 3 or xyz.shape[-1] != 3:
        raise CloudError(f"cloud xyz must have shape (H, W, 3), got {xyz.shape}")
    if rgb.shape != xyz.shape:
        raise CloudError(f"cloud rgb shape {rgb.shape} does not match xyz shape {xyz.shape}")
    if xyz.dtype.kind != "f":
        raise CloudError(f"cloud xyz must be floating point, got {xyz.dtype}")
    flat = xyz.reshape(-1, 3)
    colours = rgb.reshape(-1, 3)
    finite = np.isfinite(flat).all(axis=1)
    count = int(finite.sum())
    if count < MIN_POINTS:
        raise CloudError(f"point cloud is empty ({count} valid points of {len(flat)})")
    return Points(np.ascontiguousarray(flat[finite], dtype=np.float32),
                  np.ascontiguousarray(colours[finite]).astype(np.uint8, copy=False), len(flat))
