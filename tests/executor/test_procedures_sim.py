"""Every robot procedure in the simulator, judged by where things physically end up."""

from __future__ import annotations

import math

import numpy as np
import pytest

from services.executor.geometry import ROTATE_STEP, approach_axis
from shared.robot import ROBOT
from tests.executor.stack import Stack, texts

CUP_HEIGHT = 0.10


@pytest.fixture
def scene(stack: Stack) -> Stack:
    """The default scene, freshly loaded, grippers open."""
    for arm in ("right", "left"):
        if stack.state["robot"]["grippers"][arm] != "open":
            stack.command("open", {"arm": arm})
    stack.load_scene("default")
    return stack


def test_pick_up_lifts_the_cup_and_place_puts_it_next_to_the_other(scene: Stack) -> None:
    red_before = scene.position("obj0")
    said = scene.command("pick_up", {"arm": "right", "object": scene.pid("obj0")}, phrases={"verb": "grab"})
    assert texts(said, "narration")[0].startswith("Grabbing the")
    assert texts(said, "error") == []
    red = scene.position("obj0")
    assert red[2] > red_before[2] + 0.08, "the cup was not lifted"
    assert np.linalg.norm(red[:2] - scene.ee("right")[:2]) < 0.08, "the cup did not move with the hand"
    assert scene.state["robot"]["grippers"]["right"] == "holding"

    said = scene.command("place_rel", {"arm": "right", "relation": "left_of", "object": scene.pid("obj1")})
    assert texts(said, "error") == []
    red, blue = scene.position("obj0"), scene.position("obj1")
    assert abs(red[2] - blue[2]) < 0.01, "the cup is not standing on the table"
    assert abs(red[0] - blue[0]) < 0.04
    gap = red[1] - blue[1] - 0.07
    assert 0.02 < gap < 0.09, f"the cup is not just left of the other (gap {gap:.3f} m)"
    assert scene.state["robot"]["grippers"]["right"] == "open"


def test_move_above_puts_the_fingertips_over_the_box(scene: Stack) -> None:
    box = scene.position("obj2")
    top = box[2] + scene.truth["obj2"]["size"][2] / 2
    said = scene.command("move_rel_dest", {"arm": "left", "relation": "above", "object": scene.pid("obj2")})
    assert texts(said, "error") == []
    tool = scene.ee("left")
    assert np.linalg.norm(tool[:2] - box[:2]) < 0.03
    assert 0.07 < tool[2] - top < 0.13
    assert approach_axis(tool)[2] < -0.9, "the gripper does not face the box"


def test_directional_moves_step_ten_centimetres(scene: Stack) -> None:
    scene.command("move_rel_dest", {"arm": "right", "relation": "above", "object": scene.pid("obj0")})
    before = scene.ee("right")
    said = scene.command("move_abs_dir", {"arm": "right", "direction": "up"})
    assert texts(said, "error") == []
    after = scene.ee("right")
    assert np.allclose(after[:3] - before[:3], [0, 0, 0.10], atol=0.015)
    cup = scene.position("obj0")
    before_distance = np.linalg.norm(after[:3] - cup)
    said = scene.command("move_rel_dir", {"arm": "right", "direction": "towards", "object": scene.pid("obj0")})
    assert texts(said, "error") == []
    assert np.linalg.norm(scene.ee("right")[:3] - cup) == pytest.approx(before_distance - 0.10, abs=0.02)


def test_point_aims_the_gripper_at_the_object(scene: Stack) -> None:
    said = scene.command("point_to", {"arm": "left", "object": scene.pid("obj1")})
    assert texts(said, "error") == []
    tool = scene.ee("left")
    to_object = scene.position("obj1") - tool[:3]
    angle = math.degrees(math.acos(np.dot(approach_axis(tool), to_object) / np.linalg.norm(to_object)))
    assert angle < 12, f"the gripper points {angle:.0f}° away from the cup"


def test_look_at_centres_the_object_in_the_head_camera(scene: Stack) -> None:
    target = scene.position("obj0")
    said = scene.command("look_at", {"object": scene.pid("obj0")})
    assert texts(said, "error") == []
    pan, tilt = scene.robot["head"]["pan"], scene.robot["head"]["tilt"]
    torso = scene.robot["joints"]["torso_lift_joint"]
    pan_axis = np.array([-0.06707, 0.0, 0.790675 + torso + 0.38145])
    offset = target - pan_axis
    assert pan == pytest.approx(math.atan2(offset[1], offset[0]), abs=0.03)
    # the camera's optical axis in the vertical plane through the pan axis
    c, s = math.cos(tilt), math.sin(tilt)
    eye = np.array([0.068 - 0.14707 * c + 0.29195 * s, pan_axis[2] + 0.14707 * s + 0.29195 * c])
    seen = np.array([math.hypot(offset[0], offset[1]), target[2]]) - eye
    miss = abs(c * seen[1] + s * seen[0])
    assert miss < 0.03, f"the cup is {miss:.3f} m off the camera's axis"


def test_rotate_turns_the_wrist_by_the_step(scene: Stack) -> None:
    roll = "r_wrist_roll_joint"
    before = scene.robot["joints"][roll]
    said = scene.command("rotate", {"arm": "right", "direction": "ccw"}, phrases={"verb": "twist"})
    assert texts(said, "narration") == ["Twisting your right hand counter-clockwise."]
    assert scene.robot["joints"][roll] - before == pytest.approx(ROTATE_STEP, abs=0.05)


def test_close_then_open_and_no_op_refusals(scene: Stack) -> None:
    assert texts(scene.command("close", {"arm": "left"}), "error") == []
    assert scene.state["robot"]["grippers"]["left"] == "closed"
    with scene.unchanged_arms():
        assert texts(scene.command("close", {"arm": "left"}), "error") == ["My left hand is already closed."]
    assert texts(scene.command("open", {"arm": "left"}), "error") == []
    assert scene.state["robot"]["grippers"]["left"] == "open"
    assert texts(scene.command("open", {"arm": "left"}), "error") == ["My left hand is already open."]


def test_side_pose_and_record(scene: Stack) -> None:
    said = scene.command("move_abs_dest", {"arm": "right", "destination": "side"})
    assert texts(said, "error") == []
    joints = [scene.robot["joints"][n] for n in ROBOT.arm_joint_names("right")]
    assert np.allclose(joints, ROBOT.arm_pose("side", "right"), atol=0.05)
    said = scene.command("record")
    assert "Found 4 objects." in texts(said, "info")


def test_place_on_the_table_lowers_until_the_cup_stands(scene: Stack) -> None:
    scene.command("pick_up", {"arm": "left", "object": scene.pid("obj1")})
    assert scene.position("obj1")[2] > 0.84
    said = scene.command("place_abs", {"arm": "left", "destination": "table"})
    assert texts(said, "error") == []
    assert scene.position("obj1")[2] == pytest.approx(0.72 + CUP_HEIGHT / 2, abs=0.01)


@pytest.mark.parametrize(
    "procedure, args, expected",
    [
        ("place_abs", {"arm": "right", "destination": "table"}, "My right hand isn't holding anything to place."),
        ("pick_up", {"arm": "right", "object": "obj99"}, "I don't know any object called 'obj99'"),
        ("move_rel_dest", {"arm": "left", "relation": "under", "object": "obj0"}, "'under' is not a relation I know"),
    ],
)
def test_impossible_commands_are_refused_without_motion(
    scene: Stack, procedure: str, args: dict, expected: str
) -> None:
    with scene.unchanged_arms():
        said = scene.command(procedure, args)
    errors = texts(said, "error")
    assert len(errors) == 1 and errors[0].startswith(expected)
    assert texts(said, "narration") == []


def test_unreachable_target_is_named_and_nothing_moves(scene: Stack) -> None:
    scene.load_scene("default", poses={"obj2": [1.05, -0.45]})
    box = scene.pid("obj2")
    reach = scene.wait_for(lambda: scene.state["reach"].get(box), 10, "the reach map of the moved box")
    assert reach["left"]["above"] is False
    with scene.unchanged_arms():
        said = scene.command("move_rel_dest", {"arm": "left", "relation": "above", "object": box})
    assert texts(said, "error")[-1].startswith("I can't reach above the ")
    assert texts(said, "error")[-1].endswith("with my left hand.")
