"""Contact moves on the running stack: presses, pushing a plate, the overhang grasp, a two-hand squeeze.

Judged from the simulator's ground truth: where the plate and the box
physically are, and what the simulator's pad contacts say a gripper holds.
"""

from __future__ import annotations

import pytest

from services.sim.layout import TABLE_TOP_Z, TABLE_X
from tests.executor.stack import Stack, texts

pytestmark = [pytest.mark.slow, pytest.mark.timeout(900)]


def bottom(stack: Stack, truth_id: str) -> float:
    """Height of the object's lowest point above the table top."""
    return float(stack.truth[truth_id]["aabb"][0][2] - TABLE_TOP_Z)


def ok(said: list[dict]) -> None:
    assert texts(said, "error") == [], texts(said, "error")


@pytest.mark.parametrize("plate_x", [0.58, 0.60])
def test_plate_is_pushed_over_the_edge_and_picked_up_by_its_overhang(stack: Stack, plate_x: float) -> None:
    stack.load_scene("task5_plate_edge", poses={"obj0": [plate_x, -0.18]})
    plate = stack.pid("obj0")
    ok(stack.command("move_rel_dest", {"arm": "right", "relation": "above", "object": plate}))
    start = stack.position("obj0")

    ok(stack.command("move_abs_dir", {"arm": "right", "direction": "down"}))
    assert stack.ee("right")[2] - 0.02 > start[2], "the fingertips went into the plate"
    assert stack.ee("right")[2] - 0.02 < start[2] + 0.02, "the hand stopped short of the plate"
    assert bottom(stack, "obj0") == pytest.approx(0.0, abs=0.003), "the plate left the table"
    said = stack.command("move_abs_dir", {"arm": "right", "direction": "down"})
    assert "already pressing against" in " ".join(texts(said, "error"))

    for _ in range(2):
        ok(stack.command("move_abs_dir", {"arm": "right", "direction": "backward"}))
    pushed = stack.position("obj0")
    assert start[0] - pushed[0] > 0.15, f"the plate moved only {start[0] - pushed[0]:.3f} m"
    assert abs(pushed[1] - start[1]) < 0.03
    assert bottom(stack, "obj0") == pytest.approx(0.0, abs=0.003), "the plate tipped over the edge"
    overhang = TABLE_X[0] - (pushed[0] - stack.truth["obj0"]["dimensions"][0] / 2)
    assert overhang > 0.04

    ok(stack.command("move_abs_dir", {"arm": "right", "direction": "up"}))
    ok(stack.command("pick_up", {"arm": "right", "object": stack.pid("obj0")}))
    assert stack.robot["grippers"]["right"]["holding"] == "obj0"
    assert bottom(stack, "obj0") > 0.05, "the plate was not lifted off the table"


@pytest.mark.parametrize("plate", [[0.55, -0.10], [0.50, 0.10]])
def test_a_plate_on_the_table_is_too_wide_to_grasp(stack: Stack, plate: list[float]) -> None:
    stack.load_scene("task5_plate_edge", poses={"obj0": plate})
    with stack.unchanged_arms():
        said = stack.command("pick_up", {"arm": "right", "object": stack.pid("obj0")})
    errors = texts(said, "error")
    assert len(errors) == 1 and errors[0].endswith(
        'plate is too wide to grasp; push it over the table edge first ("push the plate towards you").'
    ), errors


@pytest.mark.parametrize("box", [[0.58, 0.0], [0.60, 0.04]])
def test_two_hands_squeeze_the_box_and_lift_it(stack: Stack, box: list[float]) -> None:
    stack.load_scene("task4_large_box", poses={"obj0": box})
    target = stack.pid("obj0")
    ok(stack.command("move_rel_dest", {"arm": "right", "relation": "right_of", "object": target}))
    ok(stack.command("move_rel_dest", {"arm": "left", "relation": "left_of", "object": stack.pid("obj0")}))
    assert stack.state["robot"]["can_move"]["right"]["left"], "a press against the box counts as a possible move"
    ok(stack.command("move_abs_dir", {"arm": "right", "direction": "left"}))
    ok(stack.command("move_abs_dir", {"arm": "left", "direction": "right"}))
    for _ in range(2):
        for arm in ("right", "left"):
            ok(stack.command("move_abs_dir", {"arm": arm, "direction": "up"}))
    lifted = bottom(stack, "obj0")
    assert lifted > 0.10, f"the box is only {lifted:.3f} m above the table"
    grippers = stack.robot["grippers"]
    assert grippers["right"]["holding"] is None and grippers["left"]["holding"] is None, (
        "a box squeezed between two hands is held by neither gripper alone"
    )
    stack.settled()
    assert bottom(stack, "obj0") > 0.10, "the box slipped"
