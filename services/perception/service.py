"""The perception service: clouds in, a stable object list out, fresh views on request.

Why it is shaped this way: clouds arrive faster than anyone needs them, so
only the newest is processed (``latest_only``); the object list is published
on a cached key so a UI started later sees it at once; a bad cloud (empty,
malformed, no table in view) never erases what we knew — the last good list is
re-published with a status that says what went wrong. ``perception/record``
answers from frames *rendered* after the request (their simulated time is not
older than the newest robot state at the request; a cloud spends a while in
rendering, encoding and transport, so one that merely *arrives* later can
still show the scene before a reload or the arms mid-motion) and agree with
each other, and never from the first frames after a scene load, while the new
objects are still waiting for their ids.
A cloud is rendered a little before it arrives, so the arms are masked at the
states that bracket its simulated time, not at the newest one. A scene load
(the cloud's own ``scene`` name or ``scene_generation`` changes) forgets every
object at once. Stopping waits for the cloud being processed and publishes
nothing afterwards, so the bus can close under it. Clouds are taken from the
bus as maps and typed here rather than by the subscription: a cloud that
does not fit its type must still be answered, with a status that says why.
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from services.perception.cloud import CloudError, camera_position
from services.perception.pipeline import Settings, detect
from services.perception.robot_mask import hides, segments_from_states
from services.perception.table_edges import TableExtent, widest
from services.perception.tracking import Tracker, TrackSettings
from shared.bus import Bus
from shared.codec import MessageError
from shared.messages import Cloud, RecordReply, SimState, as_received, reply_from, typed

log = logging.getLogger("hfpbd.perception")

OK = "ok"
SETTLE_DISTANCE = 0.01  # m two frames' positions may differ and still agree
STATE_HISTORY = 50  # sim/state messages kept (2 s at 25 Hz) to find the ones around a cloud
TABLE_MOVED = 0.02  # m the table top's height may change before its extent seen so far is forgotten


@dataclass(frozen=True)
class Frame:
    """One processed cloud, as remembered for ``record`` requests."""

    number: int
    status: str
    objects: list[dict]
    sim_time: float | None = None  # when the cloud was rendered (None: unknown)
    steady: bool = True  # enough frames since the last scene load for new objects to be confirmed


class PerceptionService:
    def __init__(
        self,
        bus: Bus,
        settings: Settings = Settings(),
        track_settings: TrackSettings = TrackSettings(),
        record_timeout: float = 5.0,
    ) -> None:
        self.bus = bus
        self.settings = settings
        self.tracker = Tracker(track_settings)
        self.record_timeout = record_timeout
        self._states: deque[SimState] = deque(maxlen=STATE_HISTORY)
        self._scene: tuple[object, object] | None = None
        self._working = threading.Lock()  # held while a cloud is processed and published
        self._stopped = False
        self._objects: list[dict] = []
        self._table: dict | None = None
        self._table_seen: TableExtent | None = None  # the table's extent as far out as it was seen in this scene
        self._frames: deque[Frame] = deque(maxlen=8)
        self._since_load = 0  # frames processed since the tracker last forgot everything
        self._changed = threading.Condition()
        self._publisher = bus.publisher(bus.keys.objects, cached=True)

    def start(self) -> None:
        """Subscribe and serve; the caller declares liveliness afterwards."""
        keys = self.bus.keys
        self.bus.subscribe(keys.sim_state, self.on_state, schema="sim_state", latest_only=True)
        self.bus.subscribe(keys.cloud, self.on_cloud, latest_only=True)
        self.bus.serve(keys.record, self.on_record)

    # -- streams -----------------------------------------------------------
    def stop(self) -> None:
        """Finish the cloud in hand and publish nothing more (call before the bus closes)."""
        with self._working:
            self._stopped = True

    def on_state(self, message: SimState) -> None:
        self._states.append(message)

    def around(self, sim_time: float | None) -> tuple[SimState | None, SimState | None]:
        """The states just after and just before ``sim_time`` (the newest one when it is unknown)."""
        states = list(self._states)
        if not states:
            return None, None
        if sim_time is None:
            return states[-1], None
        after = next((s for s in states if _sim_time(s) >= sim_time), states[-1])
        before = next((s for s in reversed(states) if _sim_time(s) <= sim_time), None)
        return after, before if before is not after else None

    def on_cloud(self, message: dict[str, Any]) -> None:
        """Process one cloud; on any problem keep the last good objects and say why."""
        with self._working:
            if not self._stopped:
                self._process(message)

    def _process(self, message: dict[str, Any]) -> None:
        try:
            cloud = typed("cloud", message)
        except MessageError as exc:
            self.bus.rejected[self.bus.keys.cloud] += 1
            self._refuse(message, f"rejected cloud: {exc}")
            return
        assert isinstance(cloud, Cloud)
        state, earlier = self.around(cloud.sim_time)
        try:
            detection = detect(cloud, state, self.settings, earlier, self.tracker.standing())
        except CloudError as exc:
            self._refuse(message, str(exc))
            return
        scene = _scene_of(cloud, state)
        if scene is not None and scene != self._scene and self._scene is not None:
            log.info("scene %s loaded (load %s): forgetting every object", *scene)
            self.tracker.reset()
            self._table_seen = None
            self._since_load = 0
        self._since_load += 1
        self._scene = scene if scene is not None else self._scene
        arms = segments_from_states([state, earlier])
        camera = camera_position(cloud)
        self._objects = self.tracker.update(
            detection.objects,
            time.monotonic(),
            state,
            hidden=lambda position: hides(camera, position, arms) or not detection.view.sees(position),
        )
        plane = detection.plane
        centre = detection.table_outline.mean(axis=0)
        height = round(plane.z_at(float(centre[0]), float(centre[1])), 4)
        if self._table is not None and abs(height - self._table["height"]) > TABLE_MOVED:
            self._table_seen = None
        self._table_seen = widest(self._table_seen, detection.table_extent)
        self._table = {
            "height": height,
            "normal": [round(float(v), 4) for v in plane.normal],
            "outline": np.round(detection.table_outline, 3).tolist(),
            **self._table_seen.message(),
        }
        self._publish(cloud.stamp, OK, cloud.sim_time)

    def _refuse(self, message: dict[str, Any], status: str) -> None:
        """Republish the last good objects with why this cloud gave none (its map: it may not type)."""
        log.warning("%s", status)
        stamp, sim_time = message.get("stamp"), message.get("sim_time")
        self._publish(
            stamp if isinstance(stamp, (int, float)) else time.time(),
            status,
            sim_time if isinstance(sim_time, (int, float)) else None,
        )

    def _publish(self, stamp: float, status: str, sim_time: float | None = None) -> None:
        message = {"stamp": float(stamp), "objects": self._objects, "status": status}
        if self._table is not None:
            message["table"] = self._table
        self._publisher.put(as_received("objects", message))
        with self._changed:
            number = self._frames[-1].number + 1 if self._frames else 1
            rendered = float(sim_time) if sim_time is not None else None
            steady = self._since_load >= self.tracker.settings.confirm_frames
            self._frames.append(Frame(number, status, self._objects, rendered, steady))
            self._changed.notify_all()

    # -- record ------------------------------------------------------------
    def on_record(self, _request: Mapping[str, Any]) -> RecordReply:
        """Objects from two consecutive good frames rendered after the request that agree."""
        deadline = time.monotonic() + self.record_timeout
        now = _sim_time(self._states[-1]) if self._states else None
        with self._changed:
            after = self._frames[-1].number if self._frames else 0
            while True:
                fresh = [f for f in self._frames if f.number > after and _rendered_since(f, now)]
                settled = _settled(fresh)
                if settled is not None:
                    table = {"table": self._table} if self._table else {}
                    return reply_from(RecordReply, {"ok": True, "objects": settled.objects, "settled": True, **table})
                left = deadline - time.monotonic()
                if left <= 0:
                    raise RuntimeError(_record_failure(fresh, self.record_timeout))
                self._changed.wait(left)


def _scene_of(cloud: Cloud, state: SimState | None) -> tuple[object, object] | None:
    """Which load of which scene a cloud shows: its own word when it carries one.

    The robot state nearest the cloud is only a fallback: a cloud rendered
    just before a reload can be paired with the first state after it (the
    load's settling advances the clock past the cloud), and the old scene's
    objects would then seed the new scene's tracks.
    """
    if cloud.scene_generation is not None:
        return cloud.scene, cloud.scene_generation
    return (state.scene, state.scene_generation) if state is not None else None


def _sim_time(state: SimState) -> float:
    return state.sim_time if state.sim_time is not None else float("inf")


def _rendered_since(frame: Frame, sim_time: float | None) -> bool:
    """Whether the frame's cloud was rendered at or after ``sim_time`` (true when either is unknown)."""
    return sim_time is None or frame.sim_time is None or not np.isfinite(sim_time) or frame.sim_time >= sim_time


def _settled(frames: list[Frame]) -> Frame | None:
    """The newest frame that is good, steady and agrees with the good, steady frame just before it."""
    for earlier, later in zip(reversed(frames[:-1]), reversed(frames)):
        if (
            earlier.status == OK
            and later.status == OK
            and earlier.steady
            and later.steady
            and _agree(earlier.objects, later.objects)
        ):
            return later
    return None


def _agree(a: list[dict], b: list[dict]) -> bool:
    """Same ids, each within ``SETTLE_DISTANCE`` of where it was."""
    where = {o["id"]: np.asarray(o["position"]) for o in a}
    if set(where) != {o["id"] for o in b}:
        return False
    return all(float(np.linalg.norm(where[o["id"]] - np.asarray(o["position"]))) <= SETTLE_DISTANCE for o in b)


def _record_failure(fresh: list[Frame], timeout: float) -> str:
    """Why no settled observation came in time, in words for the user."""
    if not fresh:
        return f"no point cloud from the simulator in {timeout:g} s — is hfpbd sim running?"
    bad = [f.status for f in fresh if f.status != OK]
    if bad and len(bad) == len(fresh):
        return f"cannot see the table: {bad[-1]}"
    return f"the scene did not settle within {timeout:g} s: objects are still moving"
