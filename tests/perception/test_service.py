"""The perception service as a real process on a private Zenoh network."""

from __future__ import annotations

import contextlib
import queue
import threading
import time
from collections.abc import Callable

import numpy as np
import pytest

from services.perception.synthetic import Box, Camera, Cylinder, Scene, render_map
from shared.bus import RemoteError
from shared.codec import decode, encode
from shared.messages import typed
from tests.waiting import eventually

SMALL = Camera(width=320, height=240)
SCENE = Scene([Cylinder((0.70, -0.15, 0.80), 0.035, 0.10, "red"), Box((0.85, 0.10, 0.79), (0.08, 0.08, 0.08), "blue")])
WITH_GREEN = Scene([*SCENE.objects, Box((0.75, 0.30, 0.79), (0.08, 0.08, 0.08), "green")])
MOVED = Scene([Cylinder((0.90, -0.30, 0.80), 0.035, 0.10, "red"), Box((0.65, 0.25, 0.79), (0.08, 0.08, 0.08), "blue")])


@pytest.fixture(scope="module")
def good_cloud() -> dict:
    return render_map(SCENE, SMALL)


def checked(received: queue.Queue[dict]) -> Callable[[dict], None]:
    """Keep each ``perception/objects`` map as published (these tests read the wire), once it types as the schema."""

    def put(message: dict) -> None:
        typed("objects", message)
        received.put(message)

    return put


class Feed:
    """Publishes clouds from the test's hub and collects what perception publishes."""

    def __init__(self, network) -> None:
        self.bus = network.hub
        self.keys = network.hub.keys
        self.cloud = self.bus.publisher(self.keys.cloud, large=True)
        self.received: queue.Queue[dict] = queue.Queue()
        self.bus.subscribe(self.keys.objects, checked(self.received))

    def once(self, cloud: dict, timeout: float = 5.0) -> dict:
        """Publish ``cloud`` once and return the object list perception published for it."""
        while not self.received.empty():
            self.received.get_nowait()
        self.cloud.put({**cloud, "stamp": time.time()})
        return self.received.get(timeout=timeout)

    def until(self, cloud: dict, accept, timeout: float = 20.0) -> dict:
        """Publish ``cloud`` again after each object list until one satisfies ``accept`` (tracks need frames)."""

        def published() -> dict | None:
            self.cloud.put({**cloud, "stamp": time.time()})
            try:
                message = self.received.get(timeout=0.2)
            except queue.Empty:  # perception was busy or not yet subscribed: send the next frame
                return None
            return message if accept(message) else None

        return eventually(published, timeout, "perception to publish the expected object list")


@pytest.fixture
def feed(network, launcher) -> Feed:
    launcher.start("perception", "--record-timeout", "2")
    return Feed(network)


def test_publishes_objects_with_ids_and_words(feed, good_cloud):
    """A cloud with no scene counters and no robot state at all: what a camera alone gives."""
    assert "scene" not in good_cloud and "scene_generation" not in good_cloud
    message = feed.until(good_cloud, lambda m: len(m["objects"]) == 2)
    assert message["status"] == "ok"
    assert {(o["id"], o["color"], o["type"]) for o in message["objects"]} == {
        ("obj0", "red", "cup"),
        ("obj1", "blue", "box"),
    }
    table = message["table"]
    assert table["height"] == pytest.approx(0.75, abs=0.005)
    assert table["edges"]["near"] == pytest.approx(SCENE.table_x[0], abs=0.006)
    assert table["extent"]["x"][0] == pytest.approx(SCENE.table_x[0], abs=0.006)


def test_late_joiner_gets_the_current_list_at_once(feed, good_cloud, network):
    feed.until(good_cloud, lambda m: len(m["objects"]) == 2)
    late: queue.Queue[dict] = queue.Queue()
    with network.open_bus() as other:
        other.subscribe(other.keys.objects, checked(late), history=True)
        message = late.get(timeout=10)
    assert len(message["objects"]) == 2


@pytest.mark.parametrize(
    "bad, status",
    [
        ({"xyz": np.full((240, 320, 3), np.nan, np.float32)}, "point cloud is empty"),
        ({"xyz": np.zeros((240, 320), np.float32)}, "shape (H, W, 3)"),
        ({"xyz": None}, "rejected cloud"),
    ],
    ids=["all-nan", "flat-array", "wrong-schema"],
)
def test_bad_cloud_keeps_the_last_good_list_and_says_why(feed, good_cloud, bad, status):
    good = feed.until(good_cloud, lambda m: len(m["objects"]) == 2)
    broken = {**good_cloud, **bad}
    if bad.get("xyz") is None:
        del broken["xyz"]
    message = feed.until(broken, lambda m: m["status"] != "ok")
    assert status in message["status"]
    assert [o["id"] for o in message["objects"]] == [o["id"] for o in good["objects"]]


def test_record_answers_from_fresh_settled_frames(feed, good_cloud):
    feed.until(good_cloud, lambda m: len(m["objects"]) == 2)
    stop = threading.Event()

    def keep_publishing() -> None:  # the next cloud once perception has answered the last one
        while not stop.is_set():
            feed.cloud.put({**good_cloud, "stamp": time.time()})
            with contextlib.suppress(queue.Empty):
                feed.received.get(timeout=1.0)

    publisher = threading.Thread(target=keep_publishing, daemon=True)
    publisher.start()
    try:
        reply = feed.bus.request(feed.keys.record, {}, timeout=10)
    finally:
        stop.set()
        publisher.join()
    assert reply["ok"] is True and reply["settled"] is True
    assert sorted(o["color"] for o in reply["objects"]) == ["blue", "red"]


def test_record_without_clouds_names_the_simulator(feed):
    with pytest.raises(RemoteError, match="no point cloud from the simulator in 2 s"):
        feed.bus.request(feed.keys.record, {}, timeout=10)


@pytest.mark.slow
def test_record_against_the_running_simulator(network, launcher):
    """End to end: ``hfpbd sim`` renders the default scene, perception answers ``record``."""
    launcher.start("sim")
    launcher.start("perception")
    reply = network.hub.request(network.hub.keys.record, {}, timeout=30)
    words = sorted((o["color"], o["type"]) for o in reply["objects"])
    assert words == [("blue", "cup"), ("green", "box"), ("red", "cup"), ("white", "plate")]
    assert all(o["held_by"] is None and o["visible"] for o in reply["objects"])


def sim_state(scene: str, sim_time: float) -> dict:
    return {
        "stamp": time.time(),
        "sim_time": sim_time,
        "joints": {},
        "ee": {},
        "grippers": {},
        "links": {},
        "scene": scene,
    }


def test_a_scene_load_announced_in_the_state_forgets_every_object(feed, good_cloud):
    state = feed.bus.publisher(feed.keys.sim_state)
    state.put(sim_state("first", 0.0))
    first = feed.until(good_cloud, lambda m: len(m["objects"]) == 2)
    state.put(sim_state("second", 1.0))
    reloaded = feed.until(
        good_cloud,
        lambda m: len(m["objects"]) == 2 and not {o["id"] for o in m["objects"]} & {o["id"] for o in first["objects"]},
    )
    assert sorted(o["color"] for o in reloaded["objects"]) == ["blue", "red"]


def test_a_cloud_says_which_scene_load_it_shows(feed, good_cloud):
    """A cloud's own scene word decides, with no robot state to pair it with."""
    first = feed.until({**good_cloud, "scene": "first", "scene_generation": 1}, lambda m: len(m["objects"]) == 2)
    reloaded = feed.until(
        {**good_cloud, "scene": "first", "scene_generation": 2},
        lambda m: len(m["objects"]) == 2 and not {o["id"] for o in m["objects"]} & {o["id"] for o in first["objects"]},
    )
    assert sorted(o["color"] for o in reloaded["objects"]) == ["blue", "red"]


class Recording:
    """A ``record`` request under way while the test feeds clouds.

    The query is sent before this returns, on the same link as the clouds
    published after it, so perception has it before it sees them.
    """

    def __init__(self, feed: Feed) -> None:
        self._replies = feed.bus.session.get(feed.keys.record, payload=encode({}), timeout=10)

    def result(self) -> dict:
        for reply in self._replies:
            assert reply.ok is not None, reply.err.payload.to_string() if reply.err else "no reply"
            return decode(reply.ok.payload.to_bytes())
        raise AssertionError("perception never answered the record request")


def test_record_ignores_clouds_rendered_before_the_request(feed):
    """A cloud that arrives after the request may have been rendered before it (a reload, a moving arm)."""
    state = feed.bus.publisher(feed.keys.sim_state)
    before, after = {**render_map(SCENE, SMALL), "sim_time": 9.0}, {**render_map(WITH_GREEN, SMALL), "sim_time": 10.5}
    state.put(sim_state("first", 9.0))
    feed.until(before, lambda m: len(m["objects"]) == 2)
    state.put(sim_state("first", 10.0))
    feed.once(before)  # a cloud after the state, answered: perception has the state
    recording = Recording(feed)
    for _ in range(3):
        feed.once(before)
    for _ in range(4):
        feed.once(after)
    reply = recording.result()
    assert sorted(o["color"] for o in reply["objects"]) == ["blue", "green", "red"]


def test_record_right_after_a_scene_load_waits_for_the_new_objects(feed):
    """The first frames after a load have no confirmed objects yet; an empty list is not the new scene."""
    state = feed.bus.publisher(feed.keys.sim_state)
    old, new = render_map(SCENE, SMALL), render_map(MOVED, SMALL)
    state.put(sim_state("first", 1.0))
    feed.until({**old, "sim_time": 1.0}, lambda m: len(m["objects"]) == 2)
    state.put(sim_state("second", 2.0))
    feed.once({**old, "sim_time": 1.0})  # a cloud after the state, answered: perception has the state
    recording = Recording(feed)
    feed.once({**old, "sim_time": 2.0})  # forgets every object; the old view starts candidates that never return
    for k in range(4):
        feed.once({**new, "sim_time": 2.2 + 0.2 * k})
    reply = recording.result()
    assert sorted((o["color"], tuple(np.round(o["position"][:2], 1))) for o in reply["objects"]) == [
        ("blue", (0.6, 0.2)),
        ("red", (0.9, -0.3)),
    ]


def test_sigterm_while_clouds_stream_in_stops_cleanly(network, launcher, good_cloud):
    process = launcher.start("perception")
    feed = Feed(network)
    feed.until(good_cloud, lambda m: len(m["objects"]) == 2)
    stop = threading.Event()

    def flood() -> None:  # as fast as the link takes them: the publisher blocks when it is full
        while not stop.is_set():
            feed.cloud.put({**good_cloud, "stamp": time.time()})

    flooding = threading.Thread(target=flood, daemon=True)
    flooding.start()
    try:
        answered = feed.received.qsize()
        eventually(lambda: feed.received.qsize() >= answered + 3, 20, "perception working through the flood")
        code = process.stop()
    finally:
        stop.set()
        flooding.join()
    log = process.log()
    assert code == 0, log
    assert "Traceback" not in log and "Undeclared" not in log, log
