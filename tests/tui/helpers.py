"""Shared pieces of the UI tests: waiting on the app, and world samples as services publish them."""

from __future__ import annotations

import asyncio
import functools
import json
import tempfile
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from textual.pilot import Pilot

from services.executor.actions_control import apply
from services.executor.store import ActionStore, atomic_write_text
from shared.bus import Bus, Publisher
from shared.config import SessionOptions
from shared.messages import Descriptions, Vocabulary
from tests.waiting import eventually, subscribed
from tui.app import PbdApp
from tui.bridge import Bridge, Poster


async def until(pilot: Pilot, condition: Callable[[], Any], timeout: float = 15.0, what: str = "") -> None:
    """Let the app run until ``condition()`` holds; fail with ``what`` after ``timeout``.

    The condition is checked on the app's own loop, once its pending messages
    have run, so it reads the app between two of its steps, never in the middle of one.
    """
    loop = asyncio.get_running_loop()

    async def settled() -> Any:
        await pilot.pause()
        return condition()

    def check() -> Any:
        return asyncio.run_coroutine_threadsafe(settled(), loop).result()

    await asyncio.to_thread(eventually, check, timeout, what)


class HubBridge(Bridge):
    """The app's bridge on a test's network: it reports itself open once the hub reaches every subscription.

    A line the hub publishes right after would otherwise be routed before the
    UI's subscription is known there, and be lost.
    """

    def __init__(self, options: SessionOptions, app: Poster, hub: Bus) -> None:
        super().__init__(options, app)
        self._hub = hub
        self.ready = threading.Event()

    def open(self) -> None:
        super().open()
        keys = self._hub.keys
        for key in (keys.say, keys.utterance, keys.nlu_result, keys.objects, keys.executor_state, keys.sim_state):
            subscribed(self._hub, key)
        self.ready.set()

    def watch_camera(self) -> None:
        super().watch_camera()
        subscribed(self._hub, self._hub.keys.cloud)


def hub_bridge(hub: Bus) -> Callable[[SessionOptions, Poster], HubBridge]:
    """What ``PbdApp(bridge=...)`` takes: the app's bridge, checked from ``hub``."""
    return functools.partial(HubBridge, hub=hub)


async def connected(pilot: Pilot, app: PbdApp) -> None:
    """Wait until the app is on the bus and, when its bridge is a ``HubBridge``, the hub reaches it."""
    await until(pilot, lambda: app.bridge.connected, what="the UI's session")
    if isinstance(app.bridge, HubBridge):
        await until(pilot, app.bridge.ready.is_set, what="the UI's subscriptions at the hub")


OBJECTS: list[dict[str, Any]] = [
    {
        "id": "obj0",
        "color": "red",
        "type": "cup",
        "position": [0.62, -0.15, 0.80],
        "size": [0.07, 0.07, 0.10],
        "held_by": None,
        "rgb": [200, 30, 30],
    },
    {
        "id": "obj1",
        "color": "blue",
        "type": "cup",
        "position": [0.58, 0.12, 0.80],
        "size": [0.07, 0.07, 0.12],
        "held_by": None,
        "rgb": [40, 60, 210],
    },
    {
        "id": "obj2",
        "color": "green",
        "type": "box",
        "position": [0.75, 0.02, 0.79],
        "size": [0.10, 0.08, 0.08],
        "held_by": None,
        "rgb": [40, 160, 60],
    },
    {
        "id": "obj3",
        "color": "white",
        "type": "plate",
        "position": [0.50, 0.30, 0.76],
        "size": [0.18, 0.18, 0.02],
        "held_by": None,
        "rgb": [230, 230, 230],
    },
]

REACH = {
    "obj0": {"right": {"pick_up": True}, "left": {"pick_up": False}},
    "obj1": {"right": {"pick_up": True}, "left": {"pick_up": True}},
    "obj2": {"right": {"pick_up": True}, "left": {"pick_up": True}},
    "obj3": {"right": {"pick_up": False}, "left": {"pick_up": True}},
}

ROBOT = {
    "grippers": {"right": "open", "left": "closed"},
    "last_arm": "right",
    "last_object": "obj0",
    "executing": False,
    "action": 1,
    "actions": [2],
    "steps": ["move your right hand above the red cup", "pick it up"],
    "progress": None,
}

SIM_STATE = {
    "sim_time": 1.0,
    "joints": {},
    "moving": {"right": False, "left": False},
    "ee": {"right": [0.45, -0.3, 0.95, 1, 0, 0, 0], "left": [0.45, 0.3, 0.95, 1, 0, 0, 0]},
    "grippers": {
        "right": {"width": 0.08, "holding": None, "contact": []},
        "left": {"width": 0.0, "holding": None, "contact": []},
    },
}

DESCRIPTIONS = {"obj0": "the red cup", "obj1": "the blue cup", "obj2": "the green box", "obj3": "the plate"}


def stage_world(hub: Bus) -> list[Publisher]:
    """Publish and serve, from ``hub``, what the four services would: a world with objects to talk about.

    The simulator's state is a plain stream (no late-joiner cache): publish
    ``SIM_STATE`` once the UI is connected.

    Returns the cached publishers; keep them referenced while the world should stay up.
    """
    for service in ("sim", "perception", "nlu", "executor"):
        hub.declare_alive(service)
    hub.serve(hub.keys.nlu_query("describe"), lambda _request: Descriptions(by_id=dict(DESCRIPTIONS)))
    hub.serve(
        hub.keys.nlu_query("vocabulary"),
        lambda _request: Vocabulary(
            words=["move", "pick", "place", "execute"], phrases=["move your right hand"], templates={}
        ),
    )
    objects = hub.publisher(hub.keys.objects, cached=True)
    objects.put({"stamp": 1.0, "objects": OBJECTS})
    state = hub.publisher(hub.keys.executor_state, cached=True)
    state.put({"stamp": 1.0, "robot": ROBOT, "reach": REACH})
    return [objects, state]


@contextmanager
def fixed_network(name: str) -> Iterator[tuple[Bus, SessionOptions]]:
    """A private network whose address reads the same on every run (for pictures of the screen).

    A Unix socket under a fixed name replaces a loopback port, whose number
    would change the status bar from run to run.
    """
    path = Path(tempfile.gettempdir()) / f"hfpbd-{name}.sock"
    path.unlink(missing_ok=True)
    endpoint = f"unixsock-stream/{path}"
    hub = Bus(SessionOptions(namespace=name, listen=(endpoint,), multicast_scouting=False))
    try:
        yield hub, SessionOptions(namespace=name, connect=(endpoint,), multicast_scouting=False)
    finally:
        hub.close()
        path.unlink(missing_ok=True)


# Three actions as a person would have taught them; creation times fixed so pictures never change.
TAUGHT = [
    (
        "stack the cups",
        1764590400.0,
        [
            "move your right hand above the red cup",
            "open your right hand",
            "pick up the red cup",
            "place it on top of the blue cup",
        ],
    ),
    (None, 1764594000.0, ["pick up the plate with your left hand", "move it up", "place it on the table"]),
    ("tidy the box", 1764597600.0, ["pick up the green box"]),
]


def teach(store: ActionStore) -> None:
    """Fill an empty store with ``TAUGHT`` (action 1 current)."""
    for name, _created, said in TAUGHT:
        store.create(name)
        for words in said:
            store.append_step({"procedure": "open", "args": {"arm": "right"}, "utterance": words})
    data = json.loads(store.path.read_text())
    for action, (_name, created, _said) in zip(data["actions"], TAUGHT, strict=True):
        action["created"] = created
    data["current"] = 1
    atomic_write_text(store.path, json.dumps(data))


def serve_actions(hub: Bus, store: ActionStore, runs: list[tuple[int, int]]) -> None:
    """Answer ``executor/control/actions`` from ``hub`` as the executor does, recording runs asked for."""

    def run(number: int, step: int) -> tuple[bool, str]:
        runs.append((number, step))
        return True, "accepted"

    hub.serve(hub.keys.executor_control("actions"), lambda request: apply(store, request, run))
