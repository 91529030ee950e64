"""Stable object ids across frames.

Why: the user says "pick it up" about the object they named a moment ago, and
recorded steps refer to ids, so an id must stay with its physical object while
it moves a little, while an arm passes over it, and while it is in a gripper.
Detections are matched to tracks by an optimal assignment (Hungarian, from
SciPy) on distance, size and colour; a new object must be seen in consecutive
frames before it gets an id (a one-frame flicker never becomes an object); an
object unseen for ``forget_after`` seconds is removed; ids are never reused.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import linear_sum_assignment

from services.perception.descriptors import Descriptor

ARMS = ("right", "left")
NO_MATCH = 1e6


@dataclass(frozen=True)
class TrackSettings:
    max_jump: float = 0.08        # m an object may move between two frames and keep its id
    forget_after: float = 3.0     # s an unseen (not held) object is still reported
    confirm_frames: int = 2       # consecutive sightings before a new object gets an id
    hold_radius: float = 0.15     # m from a holding gripper's tool frame to its object
    colour_penalty: float = 0.03  # m-equivalent cost of a colour-word change
    partial_share: float = 0.5    # a sighting with fewer points than this share is partial


@dataclass
class Track:
    descriptor: Descriptor
    last_seen: float
    hits: int = 1
    id: str = ""                       # empty until confirmed
    held_by: str | None = None
    hold_offset: np.ndarray | None = None
    visible: bool = True

    @property
    def confirmed(self) -> bool:
        return bool(self.id)


class Tracker:
    """Keeps the object list across frames; feed it every frame's detections."""

    def __init__(self, settings: TrackSettings = TrackSettings()) -> None:
        self.settings = settings
        self.tracks: list[Track] = []
        self._next_id = 0

    def update(self, detections: list[Descriptor], now: float,
               state: Mapping[str, Any] | None = None) -> list[dict]:
        """Fold one frame's detections in; return the published object list."""
        tools = _holding_tools(state)
        self._grasp_and_release(tools)
        for track in self.tracks:
            if track.held_by is not None and track.hold_offset is not None:
                track.descriptor.position = tools[track.held_by] + track.hold_offset
                track.descriptor.box_center = track.descriptor.position.copy()
        matches, unmatched = self._match(detections)
        for track, detection in matches:
            self._refresh(track, detection, now)
        seen = {id(track) for track, _ in matches}
        for track in self.tracks:
            track.visible = id(track) in seen
        fresh = [d for d in unmatched if not self._inside_held(d, tools)]
        self.tracks = [t for t in self.tracks if self._keep(t, now)]
        self.tracks += [Track(d, now) for d in fresh]
        for track in self.tracks:
            if not track.confirmed and track.hits >= self.settings.confirm_frames:
                track.id = f"obj{self._next_id}"
                self._next_id += 1
        return self.objects()

    def objects(self) -> list[dict]:
        """The confirmed objects as ``perception/objects`` items, by id number."""
        items = []
        for track in sorted((t for t in self.tracks if t.confirmed), key=lambda t: int(t.id[3:])):
            items.append({"id": track.id, **track.descriptor.as_message(),
                          "held_by": track.held_by, "visible": track.visible})
        return items

    # -- internals ---------------------------------------------------------
    def _grasp_and_release(self, tools: dict[str, np.ndarray]) -> None:
        """A gripper that starts holding takes the nearest object; one that opens lets go."""
        for track in self.tracks:
            if track.held_by is not None and track.held_by not in tools:
                track.held_by, track.hold_offset = None, None
        for arm, tool in tools.items():
            if any(t.held_by == arm for t in self.tracks):
                continue
            free = [t for t in self.tracks if t.confirmed and t.held_by is None]
            if not free:
                continue
            distances = [float(np.linalg.norm(t.descriptor.position - tool)) for t in free]
            nearest = int(np.argmin(distances))
            if distances[nearest] <= self.settings.hold_radius:
                free[nearest].held_by = arm
                free[nearest].hold_offset = free[nearest].descriptor.position - tool

    def _match(self, detections: list[Descriptor]) -> tuple[list[tuple[Track, Descriptor]], list[Descriptor]]:
        if not self.tracks or not detections:
            return [], list(detections)
        s = self.settings
        cost = np.full((len(self.tracks), len(detections)), NO_MATCH)
        for i, track in enumerate(self.tracks):
            gate = s.hold_radius if track.held_by else s.max_jump
            for j, det in enumerate(detections):
                distance = float(np.linalg.norm(track.descriptor.position - det.position))
                if distance > gate:
                    continue
                cost[i, j] = (distance + 0.5 * float(np.linalg.norm(track.descriptor.size - det.size))
                              + (s.colour_penalty if track.descriptor.color != det.color else 0.0))
        rows, cols = linear_sum_assignment(cost)
        pairs = [(self.tracks[r], detections[c]) for r, c in zip(rows, cols) if cost[r, c] < NO_MATCH]
        taken = {c for r, c in zip(rows, cols) if cost[r, c] < NO_MATCH}
        return pairs, [d for j, d in enumerate(detections) if j not in taken]

    def _refresh(self, track: Track, detection: Descriptor, now: float) -> None:
        """Take the new sighting unless it is only part of the object (occluded, or in a gripper)."""
        track.last_seen = now
        track.hits += 1
        if track.held_by is not None:
            return
        partial = detection.points < self.settings.partial_share * track.descriptor.points
        moved = float(np.linalg.norm(track.descriptor.position - detection.position))
        if partial and moved < 0.02:
            return
        track.descriptor = detection

    def _inside_held(self, detection: Descriptor, tools: dict[str, np.ndarray]) -> bool:
        """A blob at a holding gripper is the held object's visible part, not a new object."""
        return any(float(np.linalg.norm(detection.position - tool)) <= self.settings.hold_radius
                   for tool in tools.values())

    def _keep(self, track: Track, now: float) -> bool:
        if track.visible or track.held_by is not None:
            return True
        if not track.confirmed:
            return False  # a candidate must be seen in consecutive frames
        return now - track.last_seen <= self.settings.forget_after


def _holding_tools(state: Mapping[str, Any] | None) -> dict[str, np.ndarray]:
    """Tool-frame positions of the grippers that report holding something."""
    if not state:
        return {}
    grippers = state.get("grippers") or {}
    ee = state.get("ee") or {}
    tools = {}
    for arm in ARMS:
        gripper = grippers.get(arm)
        if isinstance(gripper, Mapping) and gripper.get("holding") and arm in ee:
            try:
                pose = np.asarray(ee[arm], dtype=float).reshape(-1)
            except (TypeError, ValueError):
                continue
            if len(pose) >= 3 and np.isfinite(pose[:3]).all():
                tools[arm] = pose[:3]
    return tools
