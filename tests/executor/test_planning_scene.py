"""The planning scene as a value: built from what is seen, used by an arm's model, tried for one block."""

from __future__ import annotations

import numpy as np
import pytest

from services.executor import geometry as geo
from services.executor import targets
from services.executor.kinematics import ArmKinematics
from services.executor.kinematics.scene import Carried, PlanningScene
from services.executor.planning_scene import seen
from services.executor.scene import measured
from services.executor.targets import Held
from tests.executor.test_kinematics import cup, scene_with

pytestmark = pytest.mark.unit


@pytest.fixture(scope="module")
def kin() -> ArmKinematics:
    return ArmKinematics("right")


def lifted_cup(kin: ArmKinematics) -> tuple[Held, np.ndarray]:
    """A cup held as grasped on the table, and the arm's joints with the hand 12 cm higher."""
    snap = scene_with(cup("c", 0.55, -0.20)).snapshot()
    kin.use(seen(snap, kin.arm, None))
    grasp = targets.grasps(snap.objects["c"], snap.near_edge)[0]
    grasp_q = kin.ik(grasp.grasp, check_collisions=False)
    lift_q = kin.ik(geo.shifted(grasp.grasp, [0.0, 0.0, 0.12]), seeds=[grasp_q], check_collisions=False)
    assert grasp_q is not None and lift_q is not None
    return Held("c", snap.box("c"), kin.fk(grasp_q)), lift_q


def test_the_held_object_is_no_obstacle_and_is_carried_as_measured(kin: ArmKinematics) -> None:
    held, _ = lifted_cup(kin)
    snap = scene_with(cup("c", 0.55, -0.20), cup("d", 0.60, 0.10, color="blue")).snapshot()
    scene = seen(snap, "right", held)
    assert set(scene.obstacles) == {"table", "d"}
    assert scene.carried == Carried("c", held.box, held.tool_pose)
    assert seen(snap, "left", None).carried is None and "c" in seen(snap, "left", None).obstacles


def test_a_cup_carried_up_moves_with_the_hand_from_where_it_was_grasped(kin: ArmKinematics) -> None:
    """Held as measured at the grasp, the arm elsewhere now: wherever the arm goes, the cup hangs where the
    grasp put it in the hand (12 cm up it is clear of the table, 4 cm lower than it stood it is in it)."""
    held, lift_q = lifted_cup(kin)
    scene = scene_with()
    arm = dict(zip([kin.names[i] for i in kin.arm_idx], lift_q, strict=True))
    scene.update_robot(measured({**scene.snapshot().joints(), **arm}))  # measured with the cup lifted
    kin.use(seen(scene.snapshot(), "right", held))
    assert not [pair for pair in kin.own_collisions(lift_q) if "table" in pair]
    sunk = kin.ik(geo.shifted(kin.fk(lift_q), [0.0, 0.0, -0.16]), seeds=[lift_q], check_collisions=False)
    assert sunk is not None
    assert ("held:c", "table") in kin.own_collisions(sunk) or ("table", "held:c") in kin.own_collisions(sunk)


def test_a_scene_tried_for_a_block_gives_way_to_the_one_before(kin: ArmKinematics) -> None:
    snap = scene_with(cup("c", 0.55, -0.20)).snapshot()
    now = seen(snap, "right", None)
    kin.use(now)
    spot = kin.ik(targets.grasps(snap.objects["c"], snap.near_edge)[0].grasp, check_collisions=False)
    assert spot is not None and kin.collisions(spot)  # the fingers close around the cup: it is in the way
    emptied = PlanningScene(obstacles={name: box for name, box in now.obstacles.items() if name != "c"})
    with kin.trying(emptied):
        assert kin.scene is emptied
        assert not [pair for pair in kin.collisions(spot) if "c" in pair]
    assert kin.scene is now
    assert [pair for pair in kin.collisions(spot) if "c" in pair]
