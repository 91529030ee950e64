"""IK, reachability and collision-aware planning on the project's PR2 model (no processes)."""

from __future__ import annotations

import re
import threading
import time

import numpy as np
import pytest

from services.executor import geometry as geo
from services.executor import targets
from services.executor.geometry import Box
from services.executor.kinematics import (
    CONTACT_STEP,
    MIN_LEAD,
    PLANNING_SLICE,
    PLANNING_TRIES,
    ArmKinematics,
)
from services.executor.planning_scene import seen
from services.executor.procedures import Procedures, StepFailed, place
from services.executor.procedures.grasps import grasp_plans, reached_by_lines_first, suited_first, suits
from services.executor.procedures.refusals import beyond
from services.executor.reach import REACH_KEYS, reach_map
from services.executor.scene import Scene, measured, perceived
from services.executor.targets import Held
from services.sim.layout import TABLE_TOP_Z, table_truth
from shared.contract import RELATIONS
from shared.robot import ROBOT

pytestmark = pytest.mark.unit


@pytest.fixture(scope="module")
def arms() -> dict[str, ArmKinematics]:
    return {arm: ArmKinematics(arm) for arm in ("right", "left")}


def cup(
    oid: str, x: float, y: float, color: str = "red", size: tuple[float, float, float] = (0.07, 0.07, 0.10)
) -> dict:
    return {"id": oid, "color": color, "type": "cup", "position": [x, y, TABLE_TOP_Z + size[2] / 2], "size": list(size)}


def scene_with(*objects: dict, pose: str = "untucked") -> Scene:
    scene = Scene()
    scene.update_objects(perceived(objects), table_truth())
    scene.update_robot(measured({ROBOT.torso_joint: ROBOT.working_torso, **ROBOT.arm_pose_map(pose)}))
    return scene


@pytest.mark.parametrize("relation", RELATIONS)
def test_relation_poses_are_reached_exactly(arms: dict[str, ArmKinematics], relation: str) -> None:
    snap = scene_with(cup("c", 0.55, -0.10)).snapshot()
    kin = arms["right"]
    kin.use(seen(snap, kin.arm, None))
    found = kin.first_reachable(geo.relation_candidates(relation, snap.box("c")))
    assert found is not None
    index, q = found
    wanted = geo.relation_candidates(relation, snap.box("c"))[index]
    reached = kin.fk(q)
    assert np.linalg.norm(reached[:3] - wanted[:3]) < 2e-3
    assert abs(abs(np.dot(reached[3:], wanted[3:])) - 1) < 1e-4
    assert kin.collisions(q) == []


def test_reach_map_covers_every_object_arm_and_key(arms: dict[str, ArmKinematics]) -> None:
    near, far = cup("near", 0.55, 0.0), cup("far", 1.10, -0.70, color="blue")
    reach, can_move = reach_map(arms, scene_with(near, far).snapshot(), {})
    assert set(reach) == {"near", "far"}
    for per_arm in reach.values():
        assert set(per_arm) == {"right", "left"}
        assert all(set(keys) == set(REACH_KEYS) for keys in per_arm.values())
    assert reach["near"]["right"]["pick_up"] and reach["near"]["left"]["pick_up"]
    assert not any(reach["far"]["left"][k] for k in ("pick_up", "above", "next_to", "place"))
    assert set(can_move["right"]) == set(geo.DIRECTIONS) and can_move["right"]["up"]


def test_reach_follows_objects_that_move(arms: dict[str, ArmKinematics]) -> None:
    scene = scene_with(cup("c", 0.55, -0.10))
    assert reach_map(arms, scene.snapshot(), {})[0]["c"]["right"]["above"]
    assert scene.update_objects(perceived([cup("c", 1.12, -0.75)]))
    assert not reach_map(arms, scene.snapshot(), {})[0]["c"]["right"]["above"]


def test_a_held_object_is_carried_around_obstacles(arms: dict[str, ArmKinematics]) -> None:
    """Moving a cup in hand over a tall box: no pose along the plan makes the cup (or arm) hit it."""
    kin = arms["right"]
    tall = {
        "id": "wall",
        "color": "green",
        "type": "box",
        "position": [0.55, -0.10, TABLE_TOP_Z + 0.075],
        "size": [0.10, 0.08, 0.15],
    }
    scene = scene_with(tall, cup("held", 0.55, -0.30))
    snap = scene.snapshot()
    kin.set_joints(snap.joints())
    grasp = targets.grasps(snap.objects["held"], snap.near_edge)[0]
    start = kin.ik(geo.shifted(grasp.grasp, [0, 0, 0.05]), check_collisions=False)
    kin.set_arm(start)
    held = Held("held", Box(snap.box("held").center + [0, 0, 0.05], snap.box("held").size), kin.fk())
    scene.update_robot(measured({**snap.joints(), **dict(zip([kin.names[i] for i in kin.arm_idx], start))}))
    snap = scene.snapshot()
    kin.use(seen(snap, kin.arm, held))
    goal = targets.move_relation("left_of", snap.box("wall"), kin.fk(), held, snap.table_z)[0]
    goal_q = kin.ik(goal)
    assert goal_q is not None
    trajectory = kin.plan_to(goal_q)
    assert trajectory is not None
    dense = np.vstack([np.linspace(a, b, 5) for a, b in zip(trajectory.points[:-1], trajectory.points[1:])])
    assert all(kin.collisions(q) == [] for q in dense)
    # without the held object in the model the straight joint path would have swept it through the box
    cup_path = [kin.fk(q)[:3] + held.offset for q in dense]
    assert not any(np.all(np.abs(p - snap.box("wall").center) < snap.box("wall").half + 0.035) for p in cup_path)


def test_moves_take_longer_the_further_they_go(arms: dict[str, ArmKinematics]) -> None:
    kin = arms["left"]
    kin.use(seen(scene_with().snapshot(), kin.arm, None))
    short = kin.straight_line(geo.direction_target(kin.fk(), "down", 0.05))
    long = kin.straight_line(geo.direction_target(kin.fk(), "down", 0.20))
    assert short is not None and long is not None
    assert long.duration > 1.5 * short.duration  # four times as far: twice as long while accelerating throughout


def test_planning_gives_up_when_the_user_says_stop() -> None:
    """A path that needs the random planner (a tall box between the hand and its goal) is abandoned on stop."""
    cancel = threading.Event()
    kin = ArmKinematics("right", cancel=cancel)
    wall = {
        "id": "wall",
        "color": "green",
        "type": "box",
        "position": [0.55, -0.10, TABLE_TOP_Z + 0.09],
        "size": [0.20, 0.04, 0.18],
    }
    snap = scene_with(wall).snapshot()
    kin.use(seen(snap, kin.arm, None))
    here = kin.ik(geo.make_pose([0.55, -0.25, TABLE_TOP_Z + 0.10], geo.facing([1.0, 0.0, 0.0])))
    there = kin.ik(geo.make_pose([0.55, 0.05, TABLE_TOP_Z + 0.10], geo.facing([1.0, 0.0, 0.0])))
    assert here is not None and there is not None
    kin.set_arm(here)
    assert (
        kin._joint_line(kin.arm_q, there) is None and kin._via_ready(there) is None and kin._via_lifts(there) is None
    ), "not a random planner's case"
    cancel.set()
    assert kin.plan_to(there) is None and kin.cancelled  # how soon it gives up is the executor benchmark's figure
    cancel.clear()
    started = time.perf_counter()
    # without the stop the random planner runs: it finds a path, or gives up only after its tries
    assert kin.plan_to(there) is not None or time.perf_counter() - started >= PLANNING_TRIES * PLANNING_SLICE


def test_reach_map_gives_way_to_a_command(arms: dict[str, ArmKinematics]) -> None:
    assert reach_map(arms, scene_with(cup("c", 0.55, -0.10)).snapshot(), {}, interrupted=lambda: True) is None


def test_the_model_fingers_are_set_for_a_block_only(arms: dict[str, ArmKinematics]) -> None:
    kin = arms["right"]
    kin.use(seen(scene_with().snapshot(), kin.arm, None))
    before = kin.qpos.copy()
    with kin.fingers(0.08):
        opened = kin.qpos.copy()
    assert np.array_equal(kin.qpos, before)
    fingers = [kin.index[f"r_gripper_{side}_finger_joint"] for side in ("l", "r")]
    assert np.allclose(opened[fingers], 0.04) and np.array_equal(np.delete(opened, fingers), np.delete(before, fingers))


def test_a_press_starts_with_a_stretch_clear_for_the_open_fingers(arms: dict[str, ArmKinematics]) -> None:
    """The part of a press travelled while the fingers close ends before the object and is clear with them open."""
    kin = arms["right"]
    box = {
        "id": "box",
        "color": "orange",
        "type": "box",
        "position": [0.58, 0.0, TABLE_TOP_Z + 0.09],
        "size": [0.20, 0.30, 0.18],
    }
    kin.use(seen(scene_with(box).snapshot(), kin.arm, None))
    start = kin.ik(geo.make_pose([0.58, -0.23, TABLE_TOP_Z + 0.09], geo.facing([1.0, 0.0, 0.0])))
    assert start is not None
    kin.set_arm(start)
    goal = geo.direction_target(kin.fk(), "left")
    with kin.fingers(0.0):
        move = kin.contact_line(goal)
    assert move is not None and move.touched == ("box",)
    lead = kin.free_lead(move)
    assert lead is not None and (len(lead) - 1) * CONTACT_STEP >= MIN_LEAD
    assert len(lead) <= move.lead < len(move.path)
    assert np.array_equal(lead, move.path[: len(lead)])
    assert all(kin.collisions(q) == [] for q in lead)


def test_a_hand_above_what_it_released_lifts_before_swinging_away(arms: dict[str, ArmKinematics]) -> None:
    """The joint-space lines to the side would sweep the fingers through the cup below: a lift first, no random planner."""
    kin = arms["right"]
    kin.use(seen(scene_with(cup("c", 0.62, 0.256, size=(0.072, 0.072, 0.10))).snapshot(), kin.arm, None))
    above = kin.ik(np.array([0.61, 0.259, TABLE_TOP_Z + 0.165, 0.989, 0.0, 0.0, -0.145]))
    assert above is not None
    kin.set_arm(above)
    side = np.asarray(ROBOT.arm_pose("side", "right"), float)
    assert kin._joint_line(kin.arm_q, side) is None and kin._via_ready(side) is None, "no longer a case for the lift"
    path = kin._via_lifts(side)
    assert path is not None
    assert np.array_equal(path[0], kin.arm_q) and np.array_equal(path[-1], side)
    assert kin.fk(path[1])[2] > kin.fk()[2]
    assert all(kin.collisions(q) == [] for q in path)


def test_a_cup_just_grasped_beside_the_plate_is_carried_away(arms: dict[str, ArmKinematics]) -> None:
    """The carried box overlaps the padded table and plate at the grasp: the plan still leaves, then stays clear."""
    kin = arms["right"]
    plate = {
        "id": "plate",
        "color": "white",
        "type": "plate",
        "position": [0.63, 0.0, TABLE_TOP_Z + 0.008],
        "size": [0.16, 0.16, 0.015],
    }
    scene = scene_with(plate, cup("red", 0.55, -0.12), cup("blue", 0.55, 0.12, color="blue"), pose="side")
    snap = scene.snapshot()
    kin.use(seen(snap, kin.arm, None))
    grasp = targets.grasps(snap.objects["red"], snap.near_edge)[0]
    kin.allow_touching("red", True)
    grasp_q = kin.ik(grasp.grasp, seeds=[kin.ik(grasp.pregrasp)])
    kin.allow_touching("red", False)
    assert grasp_q is not None
    scene.update_robot(measured({**snap.joints(), **dict(zip([kin.names[i] for i in kin.arm_idx], grasp_q))}))
    snap = scene.snapshot()
    kin.set_arm(grasp_q)
    held = targets.held_in_hand("red", snap.box("red"), kin.fk(), snap.table_z)
    kin.use(seen(snap, kin.arm, held))
    assert {"plate", "table"} <= {name for pair in kin.collisions(kin.arm_q) for name in pair}
    goal = targets.move_relation("above", snap.box("blue"), kin.fk(), held, snap.table_z)
    found = kin.first_reachable(goal)
    assert found is not None
    trajectory = kin.plan_to(found[1])
    assert trajectory is not None
    lifted = next(i for i, q in enumerate(trajectory.points) if not kin.collisions(q))
    assert kin.fk(trajectory.points[lifted])[2] - kin.fk(grasp_q)[2] < 0.05  # it only lifted clear of the contacts
    assert all(kin.collisions(q) == [] for q in trajectory.points[lifted:])


def test_perceptions_sighting_of_the_held_cup_is_no_obstacle(arms: dict[str, ArmKinematics]) -> None:
    """The cup perception sees in the hand (a blob of hand and cup reaching down to the table) is not an obstacle."""
    kin = arms["left"]
    scene = scene_with(pose="untucked")
    kin.set_joints(scene.snapshot().joints())
    tool = kin.fk()
    held = Held("cup", Box(tool[:3] + [0.01, 0.0, -0.01], np.array([0.07, 0.07, 0.10])), tool)
    height = float(tool[2] - TABLE_TOP_Z)
    sighting = {
        "id": "again",
        "color": "red",
        "type": "cup",
        "held_by": "left",
        "position": [float(tool[0]), float(tool[1]), TABLE_TOP_Z + height / 2],
        "size": [0.08, 0.08, height],
    }
    scene.update_objects(perceived([sighting]))
    snap = scene.snapshot()
    assert snap.supported("again")
    kin.use(seen(snap, kin.arm, None))
    assert kin.collisions(kin.arm_q) != []  # as an obstacle it would hold the hand fast
    kin.use(seen(snap, kin.arm, held))
    assert kin.collisions(kin.arm_q) == []


def test_a_cup_out_of_one_hands_reach_is_refused_with_how_far_and_the_other_hand(
    arms: dict[str, ArmKinematics],
) -> None:
    scene = scene_with(cup("c", 0.85, 0.45), pose="side")
    procedures = Procedures(scene, None, arms, list)  # type: ignore[arg-type]
    with pytest.raises(StepFailed) as refused:
        procedures.pick_up("right", "c")
    words = str(refused.value)
    assert re.fullmatch(r"The cup is \d+ cm beyond my right hand; my left hand can reach it\.", words), words
    far = int(re.search(r"(\d+) cm", words).group(1))
    assert 5 <= far <= 30


def test_a_straight_line_remembers_what_it_ran_into(arms: dict[str, ArmKinematics]) -> None:
    """What a failed placement can be blamed on: a tall cup right under the hand blocks a move down, by name."""
    kin = arms["left"]
    kin.use(seen(scene_with().snapshot(), kin.arm, None))
    below = kin.fk()[:3]
    kin.use(
        seen(
            scene_with(cup("mug", float(below[0]), float(below[1]), size=(0.08, 0.08, 0.20))).snapshot(), kin.arm, None
        )
    )
    line = kin.line(geo.direction_target(kin.fk(), "down", 0.20))
    assert line.path is None
    assert line.blocked_by == {"mug"}


def test_a_box_held_from_the_side_is_put_behind_a_cup_only_with_the_forearm_swung_past_it(
    arms: dict[str, ArmKinematics],
) -> None:
    """Left hand, a 6 cm box side-grasped at (0.655, 0.30), to go behind a 6.5 cm cup at (0.59, -0.07).

    At the usual headings the forearm behind the box comes down onto the cup;
    a wider swing takes it past the cup's side.
    """
    kin = arms["left"]
    box = {"id": "box", "color": "red", "type": "box", "position": [0.655, 0.297, TABLE_TOP_Z + 0.0295]}
    box["size"] = [0.066, 0.066, 0.059]
    scene = scene_with(box, cup("mug", 0.589, -0.071, size=(0.056, 0.056, 0.065)), pose="side")
    snap = scene.snapshot()
    kin.use(seen(snap, kin.arm, None))
    grasp_q = lifted_q = None
    for grasp in targets.grasps(snap.objects["box"], snap.near_edge):
        pre_q = kin.ik(grasp.pregrasp)
        if pre_q is None:
            continue
        kin.allow_touching("box", True)
        grasp_q = kin.ik(grasp.grasp, seeds=[pre_q])
        kin.allow_touching("box", False)
        if grasp_q is not None:
            lifted_q = kin.ik(grasp.lift, seeds=[grasp_q], check_collisions=False)
            break
    assert grasp_q is not None and lifted_q is not None
    kin.set_arm(grasp_q)
    at_grasp = targets.held_in_hand("box", snap.box("box"), kin.fk(), snap.table_z)
    scene.update_robot(measured({**snap.joints(), **dict(zip([kin.names[i] for i in kin.arm_idx], lifted_q))}))
    snap = scene.snapshot()
    procedures = Procedures(scene, None, arms, list)  # type: ignore[arg-type]
    held = procedures.refresh_held(at_grasp, snap, kin)
    kin.use(seen(snap, kin.arm, held))

    def lowerable(yaws: tuple[float, ...]) -> tuple[int, set[str]]:
        pairs = targets.place_relation("behind", snap.box("mug"), kin.fk(), held, snap.table_z, yaws)
        lowerings = [place.lowerable(kin, snap, held, hover, release) for hover, release in pairs]
        return sum(lowering.hover_q is not None for lowering in lowerings), set().union(
            *(lowering.blocked_by for lowering in lowerings)
        )

    carried, blocked_by = lowerable(targets.CARRY_YAWS)
    assert carried == 0
    assert "mug" in blocked_by
    assert lowerable(targets.SWING_YAWS)[0] > 0


def test_a_place_out_of_one_hands_reach_says_how_far_and_that_the_other_hand_can(
    arms: dict[str, ArmKinematics],
) -> None:
    """A cup in the right hand, a plate far on the left: how far beyond the right hand it is, and the left hand."""
    kin = arms["right"]
    plate = {"id": "plate", "color": "white", "type": "plate", "position": [0.65, 0.35, TABLE_TOP_Z + 0.0075]}
    plate["size"] = [0.16, 0.16, 0.015]
    scene = scene_with(plate, pose="side")
    snap = scene.snapshot()
    kin.use(seen(snap, kin.arm, None))
    tool = kin.fk()
    held = Held("c", Box(tool[:3] + [0.0, 0.0, -0.01], np.array([0.07, 0.07, 0.10])), tool)
    kin.use(seen(snap, kin.arm, held))
    procedures = Procedures(scene, None, arms, list)  # type: ignore[arg-type]
    words = beyond(procedures, kin, held, "on_top_of", snap.box("plate"), "the plate", snap.table_z, "right")
    assert words is not None
    assert re.fullmatch(
        r"I can't put it on top of the plate: the plate is \d+ cm beyond my right hand; my left hand can reach it\.",
        words,
    ), words
    procedures.set_held("left", held)  # the left hand busy: it is not offered
    words = beyond(procedures, kin, held, "on_top_of", snap.box("plate"), "the plate", snap.table_z, "right")
    assert words is not None and "left hand" not in words


def test_a_pre_grasp_a_turn_of_the_forearm_away_is_reached_with_the_rolls_a_turn_round(
    arms: dict[str, ArmKinematics],
) -> None:
    """The left hand above a box on the right, then to a cup on the left: some pre-grasps' forearm roll lies a
    turn from the ready posture's, and every joint-space line to them swings the forearm through the cups; the
    same posture with the roll a turn round is reached by lines at once, not by seconds of random planning."""
    kin = arms["left"]
    box = cup("box", 0.508, -0.165, color="green", size=(0.06, 0.06, 0.06)) | {"type": "box"}
    plate = cup("plate", 0.617, 0.035, color="white", size=(0.16, 0.16, 0.015)) | {"type": "plate"}
    snap = scene_with(cup("red", 0.453, 0.12), cup("blue", 0.464, 0.009, color="blue"), box, plate).snapshot()
    kin.use(seen(snap, kin.arm, None))
    above = kin.first_reachable(targets.move_relation("above", snap.box("box"), kin.fk(), None, snap.table_z))
    assert above is not None
    kin.set_arm(above[1])
    pre_grasps = [
        q for g in targets.grasps(snap.objects["red"], snap.near_edge) if (q := kin.ik(g.pregrasp)) is not None
    ]
    turned = [q for q in pre_grasps if kin._lines_to(q) is None]
    assert turned, "no longer a case for the turned rolls"
    for pre_q in turned:
        trajectory = kin.plan_to(pre_q)
        assert trajectory is not None
        end = trajectory.points[-1]
        turns = (end - pre_q) / (2 * np.pi)
        assert np.allclose(turns, np.round(turns), atol=1e-9) and np.any(np.round(turns) != 0)
        np.testing.assert_allclose(kin.fk(end), kin.fk(pre_q), atol=1e-6)


def test_a_pick_up_sets_off_with_a_grasp_the_lines_reach_before_one_only_the_random_planner_might(
    arms: dict[str, ArmKinematics],
) -> None:
    """From the side posture, the left hand's preferred grasp of a cup beyond the plate (a side grasp low over
    the plate) is reached by no joint-space line, and the random planner did not find it in 7 s; the next grasps
    are reached at once, so they are tried first and the preferred one after them."""
    plate = cup("plate", 0.482, 0.026, color="white", size=(0.16, 0.16, 0.015)) | {"type": "plate"}
    box = cup("box", 0.587, 0.17, color="green", size=(0.06, 0.06, 0.06)) | {"type": "box"}
    scene = scene_with(cup("red", 0.643, 0.062), cup("blue", 0.532, -0.125, color="blue"), box, plate, pose="side")
    procedures = Procedures(scene, None, arms, list)  # type: ignore[arg-type]
    kin, snap = procedures.ready("left")
    preferred = list(grasp_plans(kin, snap.objects["red"], snap.near_edge))
    assert not kin.reached_by_lines(preferred[0][1]), "no longer a case for the order"
    ordered = list(reached_by_lines_first(kin, iter(preferred)))
    assert sorted(id(c) for c in ordered) == sorted(id(c) for c in preferred)
    reached = [kin.reached_by_lines(q) for _, q in ordered]
    assert reached[0] and reached == sorted(reached, reverse=True)


def test_a_pick_up_followed_by_a_placement_grasps_so_that_it_can_be_set_down_there(
    arms: dict[str, ArmKinematics],
) -> None:
    """A cup to go behind a tall box: held as the first grasps hold it (from the robot's side), the right hand
    cannot lower it there; a grasp from further round can, and with the placement known it is tried first."""
    tall = cup("tall", 0.48, 0.0, color="blue", size=(0.1, 0.1, 0.2)) | {"type": "box"}
    scene = scene_with(cup("red", 0.6, -0.1), tall, pose="side")
    procedures = Procedures(scene, None, arms, list)  # type: ignore[arg-type]
    kin, snap = procedures.ready("right")
    obj = snap.objects["red"]
    behind = {"relation": "behind", "object": "tall"}
    plain = list(reached_by_lines_first(kin, grasp_plans(kin, obj, snap.near_edge)))
    assert not suits(procedures, kin, snap, obj, TABLE_TOP_Z, plain[0], behind), "no longer a case for the order"
    suited = list(suited_first(procedures, kin, snap, obj, TABLE_TOP_Z, iter(plain), behind))
    assert suits(procedures, kin, snap, obj, TABLE_TOP_Z, suited[0], behind)
    assert sorted(id(c) for c in suited) == sorted(id(c) for c in plain)  # the same candidates, one moved ahead
    assert [c for c in plain if c is not suited[0]] == suited[1:]
