"""The simulator as a real process: streams arrive with their fields, controls work, bad requests are refused."""

from __future__ import annotations

import math
import queue
from typing import Any

import numpy as np
import pytest

from shared.bus import Bus, RemoteError
from shared.messages import typed
from shared.robot import ROBOT
from tests.processes import Network, ServiceProcess
from tests.waiting import eventually


class Inbox:
    """Collects the messages of one key for a test to wait on."""

    def __init__(self) -> None:
        self.items: queue.Queue[Any] = queue.Queue()

    def __call__(self, message: Any) -> None:
        self.items.put(message)

    def wait(self, predicate=lambda m: True, timeout: float = 20.0) -> Any:
        """The first message that satisfies ``predicate``, the others dropped on the way."""

        def matching() -> tuple[Any] | None:
            try:
                message = self.items.get(timeout=0.2)
            except queue.Empty:
                return None
            return (message,) if predicate(message) else None

        return eventually(matching, timeout, "a matching message")[0]


@pytest.fixture(scope="module")
def client(sim_network: Network, sim_service: ServiceProcess) -> Bus:
    return sim_network.hub


@pytest.fixture(scope="module")
def events(client: Bus) -> Inbox:
    inbox = Inbox()
    client.subscribe(client.keys.sim_events, inbox, schema="sim_event")
    return inbox


def test_state_carries_every_documented_field(client: Bus) -> None:
    inbox = Inbox()
    client.subscribe(client.keys.sim_state, inbox, latest_only=True)  # the map on the wire, every field present
    state = inbox.wait()
    typed("sim_state", state)
    for field in (
        "stamp",
        "sim_time",
        "joints",
        "velocities",
        "ee",
        "grippers",
        "moving",
        "head",
        "torso",
        "links",
        "rtf",
        "scene",
        "scene_generation",
    ):
        assert field in state, field
    assert len(state["joints"]) == 21
    assert set(state["ee"]) == {"right", "left"} and len(state["ee"]["right"]) == 7
    assert state["grippers"]["right"]["width"] == pytest.approx(0.08, abs=0.002)
    assert "r_gripper_tool_frame" in state["links"] and "l_forearm_link" in state["links"]


def test_cloud_is_organised_in_the_base_frame(client: Bus) -> None:
    inbox = Inbox()
    client.subscribe(client.keys.cloud, inbox, schema="cloud", latest_only=True)
    cloud = inbox.wait()
    assert cloud.xyz.shape == (120, 160, 3) and cloud.xyz.dtype == np.float32
    assert cloud.rgb.shape == (120, 160, 3) and cloud.rgb.dtype == np.uint8
    assert (cloud.width, cloud.height) == (160, 120)
    points = cloud.xyz[np.isfinite(cloud.xyz).all(axis=2)]
    on_table = np.abs(points[:, 2] - 0.72) < 0.01
    assert on_table.mean() > 0.3
    assert 1.6 < cloud.camera_pose[2] < 2.0  # a Kinect on a raised PR2 head


def test_truth_lists_the_default_objects(client: Bus) -> None:
    inbox = Inbox()
    client.subscribe(client.keys.truth, inbox, schema="truth", latest_only=True)
    truth = inbox.wait()
    kinds = {(o.color, o.type) for o in truth.objects}
    assert {("red", "cup"), ("blue", "cup"), ("green", "box")} <= kinds


def test_gripper_motion_replies_at_once_and_reports_completion(client: Bus, events: Inbox) -> None:
    reply = client.request(client.keys.sim_control("gripper"), {"arm": "left", "width": 0.03})
    assert reply["ok"] and reply["motion_id"]
    done = events.wait(lambda e: e.motion_id == reply["motion_id"])
    assert done.status == "done"


def test_arm_trajectory_is_followed(client: Bus, events: Inbox) -> None:
    start = [-2.110, 1.230, -2.06, -1.69, 0.3, -1.32, 1.57]
    goal = [-1.8, 1.0, -2.06, -1.5, 0.3, -1.2, 1.57]
    points = np.linspace(start, goal, 5)
    reply = client.request(
        client.keys.sim_control("arm"), {"arm": "right", "points": points, "times": np.linspace(0.0, 1.5, 5)}
    )
    done = events.wait(lambda e: e.motion_id == reply["motion_id"])
    assert done.status == "done", done.message


def test_a_stopped_arm_is_reported_at_rest_on_the_step_it_halts(client: Bus, events: Inbox) -> None:
    """The state showing the arm at rest goes out within a few physics steps of the stop, not at the next tick."""
    states = Inbox()
    client.subscribe(client.keys.sim_state, states, schema="sim_state")
    names = ROBOT.arm_joint_names("left")
    start = [states.wait().joints[n] for n in names]
    goal = list(start)
    goal[0] -= 0.6  # the shoulder swings inwards, clear of the table
    reply = client.request(
        client.keys.sim_control("arm"), {"arm": "left", "points": [start, goal], "times": [0.0, 2.0]}
    )
    moving = states.wait(lambda s: max(abs(s.velocities[n]) for n in names) > 0.2)
    stop = client.request(client.keys.sim_control("stop"), {"arm": "left"})
    assert stop["stopped"] == [reply["motion_id"]]
    halted = states.wait(lambda s: s.sim_time > moving.sim_time and max(abs(s.velocities[n]) for n in names) < 0.05)
    stopped_at = events.wait(lambda e: e.motion_id == reply["motion_id"]).sim_time
    assert halted.sim_time - stopped_at < 0.03  # the steady ticks are 0.04 s apart
    later = states.wait(lambda s: s.sim_time > halted.sim_time + 0.3)
    assert max(abs(later.joints[n] - halted.joints[n]) for n in names) < 0.005  # and it stays where it halted


def test_one_request_starts_both_arms_in_the_same_step(client: Bus, events: Inbox) -> None:
    states = Inbox()
    client.subscribe(client.keys.sim_state, states, schema="sim_state")
    joints = states.wait().joints
    arms = {}
    for arm in ("right", "left"):
        names = ROBOT.arm_joint_names(arm)
        start = np.array([joints[n] for n in names])
        pan = 0.2 if arm == "right" else -0.2  # out of the tuck, away from each arm's shoulder pan limit
        goal = start + np.array([pan, -0.1, 0.0, 0.15, 0.0, 0.1, 0.0])
        arms[arm] = {"points": np.linspace(start, goal, 5), "times": np.linspace(0.0, 1.0, 5)}
    reply = client.request(client.keys.sim_control("arms"), {"arms": arms})
    ids = reply["motion_ids"]
    assert set(ids) == {"right", "left"} and ids["right"] != ids["left"]
    for arm in ("right", "left"):
        done = events.wait(lambda e, arm=arm: e.motion_id == ids[arm])
        assert done.status == "done", done.message
    seen = []
    while not states.items.empty():
        seen.append(states.items.get())
    moving = [tuple(s.moving[arm] for arm in ("right", "left")) for s in seen]
    assert (True, True) in moving
    started = next(i for i, m in enumerate(moving) if any(m))
    assert moving[started] == (True, True), "one arm started a state before the other"


BAD_REQUESTS = [
    ("arm", {"arm": "middle", "positions": [0] * 7}, "unknown arm"),
    ("arm", {"arm": "right", "positions": [0, 3.0, 0, 0, 0, 0, 0]}, "r_shoulder_lift_joint = 3.0000 is outside"),
    ("arm", {"arm": "right", "positions": [0, math.nan, 0, 0, 0, 0, 0]}, "NaN"),
    ("arm", {"arm": "right", "positions": [0, 0, 0]}, "7 numbers"),
    ("arm", {"arm": "right", "joints": ["r_elbow_joint"], "positions": [0] * 7}, "unknown or misplaced"),
    ("arm", {"arm": "right", "points": [[0] * 7, [0.5] + [0] * 6], "times": [0.0, 0.05]}, "too fast"),
    (
        "arm",
        {"arm": "right", "points": [[0] * 7, [0] * 7], "times": [0.0, 1.0], "contact": "yes"},
        "contact must be true or false",
    ),
    ("arm", {"arm": "right", "positions": [0] * 7, "contact": True}, "contact applies to timed waypoints"),
    ("arms", {"arms": {}}, "arms must map each arm"),
    ("arms", {"arms": {"right": {"positions": [0] * 7}, "middle": {"positions": [0] * 7}}}, "unknown arm 'middle'"),
    ("arms", {"arms": {"left": {"positions": [0] * 7, "contact": True}}}, "arms.left: contact applies"),
    ("gripper", {"arm": "left", "width": 0.2}, "width = 0.2 is outside"),
    ("head", {"pan": 0.0, "tilt": 2.0}, "tilt = 2 is outside"),
    ("torso", {"height": "high"}, "height must be a number"),
    ("scene", {"name": "kitchen"}, "unknown scene 'kitchen'"),
    ("step", {"steps": 10}, "paused"),
]


@pytest.mark.parametrize("name, request_, reason", BAD_REQUESTS, ids=[f"{b[0]}-{b[2][:20]}" for b in BAD_REQUESTS])
def test_bad_requests_are_refused_with_a_reason(
    client: Bus, sim_service: ServiceProcess, name: str, request_: dict, reason: str
) -> None:
    with pytest.raises(RemoteError, match=reason):
        client.request(client.keys.sim_control(name), request_)
    assert sim_service.popen.poll() is None
    assert client.request(client.keys.sim_control("pause"), {"paused": False})["ok"]


def test_pause_and_step_advance_time_exactly(client: Bus) -> None:
    paused = client.request(client.keys.sim_control("pause"), {"paused": True})
    stepped = client.request(client.keys.sim_control("step"), {"steps": 50})
    assert stepped["sim_time"] - paused["sim_time"] == pytest.approx(50 * 0.004, abs=1e-6)
    client.request(client.keys.sim_control("pause"), {"paused": False})


def test_scene_load_with_seed_and_snapshot(client: Bus) -> None:
    loaded = client.request(client.keys.sim_control("scene"), {"name": "task2_side_by_side", "seed": 3}, timeout=20)
    assert [o["id"] for o in loaded["objects"]] == ["obj0", "obj1"]
    again = client.request(client.keys.sim_control("scene"), {"name": "task2_side_by_side", "seed": 3}, timeout=20)
    assert np.allclose([o["position"] for o in loaded["objects"]], [o["position"] for o in again["objects"]], atol=1e-3)
    picture = client.request(client.keys.sim_control("snapshot"), {}, timeout=30)
    assert picture["png"][:8] == b"\x89PNG\r\n\x1a\n"
    inbox = Inbox()
    client.subscribe(client.keys.sim_state, inbox, schema="sim_state", latest_only=True)
    before = inbox.wait().scene_generation
    client.request(client.keys.sim_control("scene"), {"name": "default"}, timeout=20)
    state = inbox.wait(lambda m: m.scene_generation != before)
    assert state.scene == "default" and state.scene_generation == before + 1
