"""The richer conversation on the running stack: compounds, distances, undo, repeat, both hands, answers.

Commands arrive as the NLU publishes them (``nlu/result``, with ``then``,
``distance`` and ``arm: both`` as the design notes fix them); outcomes are
judged from the simulator's ground truth (``sim/truth``, and ``sim/state``
for the tool frames, the grippers and when each arm moved).
"""

from __future__ import annotations

import queue
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from services.sim.layout import TABLE_TOP_Z
from tests.executor.stack import Stack, texts

pytestmark = [pytest.mark.slow, pytest.mark.timeout(1200)]


def ok(said: list[dict]) -> None:
    assert texts(said, "error") == [], texts(said, "error")


def tilt(pose: list[float]) -> float:
    """Degrees between an object's own up axis and the vertical (pose quaternion w, x, y, z)."""
    up = Rotation.from_quat(np.roll(np.asarray(pose[3:], float), -1)).apply([0.0, 0.0, 1.0])
    return float(np.degrees(np.arccos(np.clip(up[2], -1.0, 1.0))))


def steps_of(stack: Stack) -> list[str]:
    return list(stack.state["robot"]["steps"])


class Recorder:
    """Every ``sim/state`` and ``sim/truth`` sample while recording (for timing and tilt)."""

    def __init__(self, stack: Stack) -> None:
        self.states: list[dict[str, Any]] = []
        self.truths: list[dict[str, Any]] = []
        self._on = False
        self._lock = threading.Lock()
        stack.hub.subscribe(stack.hub.keys.sim_state, lambda m: self._keep(self.states, m))
        stack.hub.subscribe(stack.hub.keys.truth, lambda m: self._keep(self.truths, m))

    def _keep(self, into: list[dict[str, Any]], message: dict[str, Any]) -> None:
        with self._lock:
            if self._on:
                into.append(message)

    @contextmanager
    def recording(self) -> Iterator[Recorder]:
        with self._lock:
            self.states.clear()
            self.truths.clear()
            self._on = True
        try:
            yield self
        finally:
            with self._lock:
                self._on = False

    def moving_span(self, arm: str) -> tuple[float, float]:
        """Simulated times of the first and the last state with the arm moving."""
        times = [s["sim_time"] for s in self.states if s["moving"].get(arm)]
        assert times, f"the {arm} arm never moved"
        return times[0], times[-1]


@pytest.fixture(scope="module")
def recorder(stack: Stack) -> Recorder:
    return Recorder(stack)


def test_nothing_to_repeat_nothing_to_undo_and_answers_move_nothing(stack: Stack) -> None:
    stack.load_scene("default")
    with stack.unchanged_arms():
        said = stack.command("repeat", utterance="again")
        assert texts(said, "error") == ["There is nothing to repeat yet: tell me what to do first."]
        said = stack.command("undo", utterance="undo")
        assert texts(said, "error") == ["There is nothing to undo: nothing has been taught yet."]
        counts = list(stack.state["robot"]["actions"])
        start = len(stack.lines)
        stack.hub.publish(
            stack.hub.keys.nlu_result,
            {"kind": "answer", "topic": "scene", "utterance": "what do you see", "text": "I see a red cup."},
        )
        stack.caught_up()
        assert stack.lines[start:] == [], "the executor said something about an answer"
        assert stack.state["robot"]["busy"] is None and stack.state["robot"]["actions"] == counts


def test_a_question_during_a_motion_is_answered_at_once_and_moves_nothing_else(stack: Stack) -> None:
    """Asked through the real NLU while the executor is busy with a motion: answered then, not after it."""
    stack.launcher.start("nlu")
    answers: queue.Queue[tuple[float, bool, dict[str, Any]]] = queue.Queue()

    def on_result(message: dict[str, Any]) -> None:  # when it came, and whether the move was still running then
        if message["kind"] == "answer":
            answers.put((time.monotonic(), bool(stack.state and stack.state["robot"]["busy"]), message))

    stack.hub.subscribe(stack.hub.keys.nlu_result, on_result)
    stack.load_scene("default")
    stack.command("move_abs_dest", {"arm": "left", "destination": "side"})
    ok(stack.command("create_action", utterance="create a new action"))
    right = stack.ee("right")[:3]
    stack.command("move_rel_dest", {"arm": "left", "relation": "above", "object": stack.pid("obj1")}, wait=False)
    stack.wait_for(lambda: stack.robot["moving"]["left"], 20, "the left arm to start moving")
    start = len(stack.lines)
    asked = time.monotonic()
    stack.hub.publish(stack.hub.keys.utterance, {"text": "what are you holding", "source": "script"})
    came, busy, answer = answers.get(timeout=10)
    assert came - asked < 2.0, f"answered {came - asked:.2f} s after the question"
    assert busy, "the answer waited for the motion to end"
    assert answer["topic"] == "holding" and "my left hand is empty" in answer["text"], answer
    spoken = stack.wait_for(lambda: texts(stack.lines[start:], "info"), 5, "the answer said")
    assert spoken == [answer["text"]]

    stack.idle()
    stack.caught_up()
    assert texts(stack.lines[start:], "error") == [] and texts(stack.lines[start:], "narration") == []
    assert np.linalg.norm(stack.ee("right")[:3] - right) < 0.01, "the right arm moved"
    assert len(steps_of(stack)) == 1, "the question was recorded as a step"


def test_a_compound_puts_the_red_cup_on_the_plate_as_two_steps(stack: Stack) -> None:
    stack.load_scene("default")
    ok(stack.command("create_action", utterance="create a new action"))
    cup, plate = stack.pid("obj0"), stack.pid("obj3")
    with stack.unchanged_arms():  # a compound that fails at once: the first step's reason, and what was left undone
        said = stack.command(
            "place_rel",
            {"arm": "right", "relation": "on_top_of", "object": plate},
            then=[{"procedure": "move_abs_dir", "args": {"arm": "right", "direction": "up"}}],
            utterance="put it on the plate and lift it",
        )
    assert texts(said, "error") == [
        "My right hand isn't holding anything to place. That was step 1 of 2; "
        "I didn't go on with moving your right hand up."
    ]
    assert steps_of(stack) == []

    said = stack.command(
        "pick_up",
        {"arm": "right", "object": cup},
        utterance="put the red cup on the plate",
        then=[{"procedure": "place_rel", "args": {"arm": "right", "relation": "on_top_of", "object": plate}}],
    )
    ok(said)
    narrated = texts(said, "narration")
    assert [line.split()[0] for line in narrated] == ["Picking", "Placing"] and "plate" in narrated[1]
    stack.settled()
    red, dish = stack.truth["obj0"], stack.truth["obj3"]
    assert np.linalg.norm(np.asarray(red["position"][:2]) - dish["position"][:2]) < dish["dimensions"][0] / 2
    assert red["aabb"][0][2] > dish["aabb"][1][2] - 0.005, "the cup is not standing on the plate"
    assert stack.robot["grippers"]["right"]["holding"] is None
    assert len(steps_of(stack)) == 2


def test_moving_a_cup_5_cm_right_carries_it_there_and_sets_it_down_upright(stack: Stack) -> None:
    """ "Move the red cup 5 cm to the right" with empty hands: pick up, the move, a put-down (three steps)."""
    stack.load_scene("default")
    ok(stack.command("create_action", utterance="create a new action"))
    before = stack.position("obj0")
    said = stack.command(
        "pick_up",
        {"arm": "right", "object": stack.pid("obj0")},
        utterance="move the red cup 5 cm to the right",
        then=[
            {"procedure": "move_abs_dir", "args": {"arm": "right", "direction": "right", "distance": 0.05}},
            {"procedure": "place_abs", "args": {"arm": "right", "destination": "table"}},
        ],
    )
    ok(said)
    stack.settled()
    after = stack.position("obj0")
    np.testing.assert_allclose(after[:2] - before[:2], [0.0, -0.05], atol=0.015)
    assert abs(after[2] - before[2]) < 0.005, "the cup is not standing on the table"
    assert tilt(stack.truth["obj0"]["pose"]) < 10
    assert stack.robot["grippers"]["right"]["holding"] is None
    assert len(steps_of(stack)) == 3


def test_distances_repeat_and_undo_walk_back_step_by_step(stack: Stack) -> None:
    stack.load_scene("default")
    ok(stack.command("create_action", utterance="create a new action"))
    ok(stack.command("move_rel_dest", {"arm": "right", "relation": "above", "object": stack.pid("obj0")}))
    poses = [stack.ee("right")[:3]]
    ok(
        stack.command(
            "move_abs_dir",
            {"arm": "right", "direction": "up", "distance": 0.05},
            utterance="right hand up 5 centimetres",
        )
    )
    poses.append(stack.ee("right")[:3])
    assert poses[1][2] - poses[0][2] == pytest.approx(0.05, abs=0.01)
    assert np.linalg.norm(poses[1][:2] - poses[0][:2]) < 0.01

    said = stack.command("repeat", utterance="again")
    ok(said)
    assert texts(said, "narration") == ["Moving your right hand 5 centimetres up."]
    poses.append(stack.ee("right")[:3])
    assert poses[2][2] - poses[1][2] == pytest.approx(0.05, abs=0.01)

    ok(stack.command("move_abs_dir", {"arm": "right", "direction": "backward", "distance": 0.15}))
    poses.append(stack.ee("right")[:3])
    assert poses[2][0] - poses[3][0] == pytest.approx(0.15, abs=0.01)
    assert len(steps_of(stack)) == 4

    for back in (2, 1, 0):  # three undos: backward, the repeat, the first lift
        said = stack.command("undo", utterance="undo")
        ok(said)
        assert texts(said, "info")[-1].startswith("Took back step")
        assert np.linalg.norm(stack.ee("right")[:3] - poses[back]) < 0.01, f"not back at pose {back}"
    assert len(steps_of(stack)) == 1
    ok(stack.command("undo", utterance="undo"))  # the move above the cup: the arm returns to the side
    assert steps_of(stack) == []
    with stack.unchanged_arms():
        said = stack.command("undo", utterance="undo")
    assert texts(said, "error") == [
        f"There is nothing to undo in action {stack.state['robot']['action']}: it has no steps."
    ]


def test_undo_puts_a_picked_cup_back_and_picks_a_placed_one_up_again(stack: Stack) -> None:
    stack.load_scene("default")
    ok(stack.command("create_action", utterance="create a new action"))
    stood = stack.position("obj1")
    ok(stack.command("pick_up", {"arm": "left", "object": stack.pid("obj1")}))
    assert stack.robot["grippers"]["left"]["holding"] == "obj1"
    said = stack.command("undo", utterance="undo")
    ok(said)
    stack.settled()
    assert stack.robot["grippers"]["left"]["holding"] is None
    back = stack.position("obj1")
    assert np.linalg.norm(back[:2] - stood[:2]) < 0.02, f"the cup is {np.linalg.norm(back[:2] - stood[:2]):.3f} m off"
    assert stack.truth["obj1"]["aabb"][0][2] - TABLE_TOP_Z < 0.005, "the cup is not standing on the table"
    assert steps_of(stack) == []

    ok(stack.command("pick_up", {"arm": "left", "object": stack.pid("obj1")}))
    ok(stack.command("place_abs", {"arm": "left", "destination": "table"}))
    assert stack.robot["grippers"]["left"]["holding"] is None
    ok(stack.command("undo", utterance="undo"))
    assert stack.robot["grippers"]["left"]["holding"] == "obj1", "the placed cup was not picked up again"
    assert stack.truth["obj1"]["aabb"][0][2] - TABLE_TOP_Z > 0.05
    assert len(steps_of(stack)) == 1


def test_both_hands_move_together_and_one_holding_refuses_open_both(stack: Stack, recorder: Recorder) -> None:
    stack.load_scene("default")
    ok(stack.command("create_action", utterance="create a new action"))
    start = {arm: stack.ee(arm)[:3] for arm in ("right", "left")}
    with recorder.recording():
        said = stack.command(
            "move_abs_dir",
            {"arm": "both", "direction": "up", "distance": 0.08},
            utterance="both hands up 8 centimetres",
        )
    ok(said)
    assert texts(said, "narration") == ["Moving both hands 8 centimetres up."]
    for arm in ("right", "left"):
        assert stack.ee(arm)[2] - start[arm][2] == pytest.approx(0.08, abs=0.01), arm
    (r0, r1), (l0, l1) = recorder.moving_span("right"), recorder.moving_span("left")
    # one two-arm request: both start in the same physics step and, on one time law, finish together
    assert abs(r0 - l0) <= 0.05 and abs(r1 - l1) <= 0.05, f"right {r0:.3f}-{r1:.3f}, left {l0:.3f}-{l1:.3f}"
    assert len(steps_of(stack)) == 1

    ok(stack.command("close", {"arm": "both"}, utterance="close both hands"))
    assert stack.state["robot"]["grippers"] == {"right": "closed", "left": "closed"}
    ok(stack.command("open", {"arm": "both"}, utterance="open both hands"))
    assert stack.state["robot"]["grippers"] == {"right": "open", "left": "open"}
    assert len(steps_of(stack)) == 3

    ok(stack.command("pick_up", {"arm": "right", "object": stack.pid("obj0")}))
    with stack.unchanged_arms():
        said = stack.command("open", {"arm": "both"}, utterance="open both hands")
    refusal = texts(said, "error")
    assert len(refusal) == 1 and refusal[0].startswith("My right hand is holding the ") and "cup" in refusal[0]
    assert refusal[0].endswith(", so I won't open both hands; tell me which hand to open."), refusal
    assert stack.robot["grippers"]["right"]["holding"] == "obj0"
    lifted = stack.position("obj0")[2]
    ok(stack.command("move_abs_dir", {"arm": "both", "direction": "up", "distance": 0.05}))  # carried along
    assert stack.position("obj0")[2] - lifted == pytest.approx(0.05, abs=0.01)
    assert stack.robot["grippers"]["right"]["holding"] == "obj0"


def test_undo_during_execution_is_refused(stack: Stack) -> None:
    stack.load_scene("default")
    ok(stack.command("create_action", utterance="create a new action"))
    ok(stack.command("move_abs_dir", {"arm": "left", "direction": "up"}))
    ok(stack.command("move_abs_dir", {"arm": "both", "direction": "forward", "distance": 0.05}))
    number = stack.state["robot"]["action"]
    stack.command("execute", utterance="execute", wait=False)
    stack.wait_for(lambda: stack.state["robot"]["executing"], 20, "the action to start")
    start = len(stack.lines)
    stack.command("undo", utterance="undo", wait=False)
    refusal = stack.wait_for(lambda: texts(stack.lines[start:], "error"), 10, "a refusal")
    assert refusal[0] == f"I can't undo a step while I'm executing action {number}; say \"stop\" first."
    stack.idle(180)
    assert f"Completed action {number}." in texts(stack.lines[start:], "narration")
    assert len(steps_of(stack)) == 2


def test_the_box_rises_level_between_both_hands_and_comes_back_down(stack: Stack, recorder: Recorder) -> None:
    stack.load_scene("task4_large_box", poses={"obj0": [0.58, 0.0]})
    ok(stack.command("create_action", utterance="create a new action"))
    ok(stack.command("move_rel_dest", {"arm": "right", "relation": "right_of", "object": stack.pid("obj0")}))
    ok(stack.command("move_rel_dest", {"arm": "left", "relation": "left_of", "object": stack.pid("obj0")}))
    ok(stack.command("move_abs_dir", {"arm": "right", "direction": "left"}))
    ok(stack.command("move_abs_dir", {"arm": "left", "direction": "right"}))
    resting = stack.truth["obj0"]["aabb"][0][2]
    with recorder.recording():
        ok(
            stack.command(
                "move_abs_dir",
                {"arm": "both", "direction": "up", "distance": 0.15},
                utterance="both hands up 15 centimetres",
            )
        )
        stack.settled()
    lifted = stack.truth["obj0"]["aabb"][0][2] - resting
    assert lifted > 0.10, f"the box rose only {lifted:.3f} m"
    worst = max(tilt(o["pose"]) for t in recorder.truths for o in t["objects"] if o["id"] == "obj0")
    assert worst < 5.0, f"the box tilted {worst:.1f} degrees on the way up"

    ok(stack.command("undo", utterance="undo"))  # both hands go back down, still squeezing: the box is set down
    stack.settled()
    assert stack.truth["obj0"]["aabb"][0][2] - resting < 0.01, "the box was not set back down"
