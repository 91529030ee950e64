"""The conversation additions without the simulator: compounds, both hands, distances, the two-arm time law."""

from __future__ import annotations

import re
from typing import Any

import numpy as np
import pytest

from services.executor import wording
from services.executor.bimanual import (
    MIN_DURATION,
    PEAK_ACCELERATION,
    first_clash,
    timed_together,
)
from services.executor.commands import CommandError, check, check_compound
from services.executor.kinematics import CAREFUL_ACCEL, CAREFUL_SPEED, ArmKinematics, joint_names
from shared.codec import MessageError
from shared.messages import NluResult, typed
from shared.robot import ROBOT


def result(fields: dict[str, Any]) -> NluResult:
    """An ``nlu/result`` command as the bus hands it to the executor."""
    message = typed("nlu_result", {"kind": "command", "utterance": "", **fields})
    assert isinstance(message, NluResult)
    return message


def refer(oid: str) -> str:
    return {"obj0": "the red cup", "obj1": "the plate"}[oid]


def test_a_compound_is_its_steps_in_order_with_their_own_words() -> None:
    steps = check_compound(
        result(
            {
                "procedure": "pick_up",
                "args": {"arm": "right", "object": "obj0"},
                "phrases": {"verb": "put"},
                "text": "pick up the red cup",
                "then": [
                    {
                        "procedure": "place_rel",
                        "phrases": {"relation": "on"},
                        "args": {"arm": "right", "relation": "on_top_of", "object": "obj1"},
                    }
                ],
            }
        )
    )
    assert [(s.procedure, s.args) for s in steps] == [
        ("pick_up", {"arm": "right", "object": "obj0"}),
        ("place_rel", {"arm": "right", "relation": "on_top_of", "object": "obj1"}),
    ]
    assert steps[0].phrases == {} and steps[1].phrases == {"relation": "on"}  # "put" is not how to say pick up
    assert steps[0].text == "pick up the red cup" and steps[1].text == ""


@pytest.mark.parametrize(
    "then, message",
    [
        (
            [{"procedure": "place_rel", "args": {"arm": "right", "relation": "under", "object": "obj1"}}],
            "I can't do step 2 of that: 'under' is not a relation I know",
        ),
        ([{"procedure": "execute", "args": {}}], "I can't do step 2 of that: execute has to be said on its own."),
    ],
)
def test_a_bad_later_step_refuses_the_whole_compound(then: object, message: str) -> None:
    with pytest.raises(CommandError) as caught:
        check_compound(result({"procedure": "open", "args": {"arm": "left"}, "then": then}))
    assert message in str(caught.value)


@pytest.mark.parametrize(
    "then, where",
    [(["place it"], "$.then[0]"), ({"procedure": "open"}, "$.then"), ([{"args": {}}], "$.then[0]")],
    ids=["not-a-command", "not-a-list", "no-procedure"],
)
def test_a_malformed_later_step_never_reaches_the_executor(then: object, where: str) -> None:
    with pytest.raises(MessageError, match=re.escape(where)):
        result({"procedure": "open", "args": {"arm": "left"}, "then": then})


def test_both_hands_only_where_the_contract_allows_them() -> None:
    for procedure, args in [
        ("open", {}),
        ("close", {}),
        ("move_abs_dir", {"direction": "up"}),
        ("move_abs_dest", {"destination": "side"}),
    ]:
        assert check(procedure, {"arm": "both", **args})["arm"] == "both"
    with pytest.raises(CommandError) as caught:
        check("pick_up", {"arm": "both", "object": "obj0"})
    assert str(caught.value) == "I can't pick something up with both hands at once; tell me which hand to use."


def test_distances_are_metres_within_the_limits() -> None:
    assert check("move_abs_dir", {"arm": "right", "direction": "up", "distance": 0.05})["distance"] == 0.05
    assert "distance" not in check("move_abs_dir", {"arm": "right", "direction": "up"})
    for bad, message in [
        (0.5, "I can move 1 to 30 centimetres at a time, not 50."),
        (0.001, "I can move 1 to 30 centimetres at a time, not 0."),
        ("far", "The distance must be a number of metres."),
        (True, "The distance must be a number of metres."),
    ]:
        with pytest.raises(CommandError) as caught:
            check("move_rel_dir", {"arm": "left", "direction": "towards", "object": "obj0", "distance": bad})
        assert str(caught.value) == message
    with pytest.raises(CommandError, match="doesn't take a distance"):
        check("rotate", {"arm": "left", "direction": "cw", "distance": 0.1})


@pytest.mark.parametrize(
    "procedure, args, expected",
    [
        ("move_abs_dir", {"arm": "both", "direction": "up"}, "Moving both hands up."),
        ("open", {"arm": "both"}, "Opening both hands."),
        (
            "move_abs_dir",
            {"arm": "right", "direction": "up", "distance": 0.05},
            "Moving your right hand 5 centimetres up.",
        ),
        (
            "move_rel_dir",
            {"arm": "left", "direction": "towards", "object": "obj1", "distance": 0.01},
            "Moving your left hand 1 centimetre towards the plate.",
        ),
    ],
)
def test_narration_of_both_hands_and_distances(procedure: str, args: dict, expected: str) -> None:
    assert wording.narration(procedure, args, {}, refer) == expected


def test_both_paths_share_start_end_and_time_law_within_the_speed_limit() -> None:
    right = np.linspace(np.zeros(7), np.full(7, 0.4), 11)
    left = np.linspace(np.zeros(7), np.full(7, -0.1), 11)
    timed = timed_together({"right": right, "left": left, "still": np.zeros((1, 7))})
    assert {t.times[0] for t in timed.values()} == {0.0}
    assert len({t.times[-1] for t in timed.values()}) == 1
    np.testing.assert_allclose(timed["right"].times, timed["left"].times)  # the same share of the way at each instant
    for t in timed.values():
        assert np.all(np.diff(t.times) > 0)
        speed = np.max(np.abs(np.diff(t.points, axis=0)), axis=1) / np.diff(t.times)
        assert np.max(speed) <= CAREFUL_SPEED + 1e-6
    # no slower than it must be: the right arm's 0.4 rad at the minimum-jerk law's peak acceleration
    assert timed["right"].duration == pytest.approx(np.sqrt(PEAK_ACCELERATION * 0.4 / CAREFUL_ACCEL), rel=1e-6)
    fast = timed_together({"right": np.linspace(np.zeros(7), np.full(7, 0.01), 30)})["right"]
    speed = np.max(np.abs(np.diff(fast.points, axis=0)) / np.diff(fast.times)[:, None])
    assert fast.duration == MIN_DURATION and speed < CAREFUL_SPEED


@pytest.fixture(scope="module")
def arms() -> dict[str, ArmKinematics]:
    return {arm: ArmKinematics(arm, seeds=500) for arm in ("right", "left")}


def test_arms_swinging_into_each_other_are_caught_and_apart_they_pass(arms: dict[str, ArmKinematics]) -> None:
    side = {arm: np.asarray(ROBOT.arm_pose("side", arm), float) for arm in arms}
    for kin in arms.values():
        for each in arms:
            kin.set_joints(dict(zip(joint_names(each), side[each])))
    # shoulder pans swung towards the middle and past it: the forearms cross in front of the body
    across = {"right": side["right"] + [1.2, 0, 0, 0, 0, 0, 0], "left": side["left"] + [-1.2, 0, 0, 0, 0, 0, 0]}
    crossing = timed_together({arm: np.linspace(side[arm], across[arm], 20) for arm in arms})
    assert first_clash(arms, crossing) is not None
    apart = {"right": side["right"] + [0, 0, 0, 0.3, 0, 0, 0], "left": side["left"] + [0, 0, 0, 0.3, 0, 0, 0]}
    parallel = timed_together({arm: np.linspace(side[arm], apart[arm], 20) for arm in arms})
    assert first_clash(arms, parallel) is None
    for arm, kin in arms.items():
        np.testing.assert_allclose(kin.arm_q, side[arm])  # the models are put back
