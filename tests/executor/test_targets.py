"""Placement candidates for a held object: where it may be released and how the hand may turn it (no processes)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from services.executor import geometry as geo
from services.executor import targets
from services.executor.geometry import Box
from services.executor.kinematics import ArmKinematics
from services.executor.kinematics.scene import Carried
from services.executor.planning_scene import seen
from services.executor.procedures.spots import back_where_lifted, on_the_table
from services.executor.scene import Scene, measured, perceived
from services.executor.targets import Held
from services.sim.layout import TABLE_TOP_Z, TABLE_X, table_truth
from shared.messages import PerceivedObject
from shared.robot import ROBOT

pytestmark = pytest.mark.unit

CUP = np.array([0.07, 0.07, 0.10])
SIDE_GRASP = geo.make_pose(
    [0.55, -0.10, 0.84], geo.facing([1.0, -0.2, 0.0])
)  # level, pointing ahead and a little right


def standing(x: float, y: float, size: np.ndarray = CUP) -> Box:
    return Box(np.array([x, y, TABLE_TOP_Z + size[2] / 2]), np.asarray(size, float))


def held_cup(tool: np.ndarray = SIDE_GRASP) -> Held:
    """A cup squeezed 1 cm in front of the tool frame, 2 cm below it."""
    return Held("cup", Box(tool[:3] + geo.approach_axis(tool) * 0.01 + [0.0, 0.0, -0.02], CUP), tool)


@pytest.mark.parametrize("relation", ["left_of", "right_of", "in_front_of", "behind"])
def test_side_placements_stand_the_object_beside_the_landmark_upright(relation: str) -> None:
    landmark, held = standing(0.60, 0.05), held_cup()
    pairs = targets.place_relation(relation, landmark, held.tool_pose, held, TABLE_TOP_Z)
    assert len(pairs) > 1
    outward = {"left_of": [0, 1], "right_of": [0, -1], "in_front_of": [-1, 0], "behind": [1, 0]}[relation]
    for hover, release in pairs:
        center = held.center_at(release)
        gap = float(np.dot(center[:2] - landmark.center[:2], outward)) - landmark.half[0] - CUP[0] / 2
        assert geo.CLOSE_GAP - 1e-6 <= gap <= geo.GAP + geo.PLACE_SHIFT + 1e-6
        assert center[2] - CUP[2] / 2 == pytest.approx(TABLE_TOP_Z + geo.RELEASE_CLEARANCE)
        # only turned about the vertical: the approach axis keeps its tilt, so the cup is never tipped
        assert geo.approach_axis(release)[2] == pytest.approx(geo.approach_axis(held.tool_pose)[2], abs=1e-9)
        assert np.allclose(hover[:3] - release[:3], [0.0, 0.0, targets.HOVER])


@pytest.mark.parametrize(
    ("size", "centres"), [((0.08, 0.08, 0.10), 1), ((0.20, 0.20, 0.10), 5)], ids=["cup-on-a-cup", "into-a-wide-box"]
)
def test_on_top_placements_keep_the_whole_object_over_the_top(size: tuple[float, float, float], centres: int) -> None:
    landmark, held = standing(0.58, 0.10, np.array(size)), held_cup()
    pairs = targets.place_relation("on_top_of", landmark, held.tool_pose, held, TABLE_TOP_Z)
    assert len(pairs) == centres * len(targets.CARRY_YAWS)
    for _, release in pairs:
        center = held.center_at(release)
        assert np.all(np.abs(center[:2] - landmark.center[:2]) + CUP[:2] / 2 <= landmark.half[:2] + 1e-9)
        assert center[2] - CUP[2] / 2 == pytest.approx(landmark.top + geo.RELEASE_CLEARANCE)


def test_the_held_object_turns_with_the_hand() -> None:
    held = held_cup()
    centre = held.center_at(held.tool_pose)
    turned = geo.carry_pose(held.tool_pose, centre, centre + [0.0, 0.1, 0.0], yaw=0.7)
    assert held.center_at(turned) == pytest.approx(centre + [0.0, 0.1, 0.0])


def test_a_turned_heading_reaches_where_the_grasp_heading_does_not() -> None:
    """Right hand, cup side-grasped at (0.54, -0.11), to be put behind a cup at (0.47, 0.0)."""
    kin = ArmKinematics("right")
    scene = Scene()
    red, blue = standing(0.54, -0.11), standing(0.47, 0.0)
    scene.update_objects(
        perceived(
            [
                {
                    "id": "blue",
                    "color": "blue",
                    "type": "cup",
                    "position": blue.center.tolist(),
                    "size": blue.size.tolist(),
                }
            ]
        ),
        table_truth(),
    )
    scene.update_robot(measured({ROBOT.torso_joint: ROBOT.working_torso, **ROBOT.arm_pose_map("side")}))
    kin.use(seen(scene.snapshot(), kin.arm, None))
    red_cup = PerceivedObject(id="red", type="cup", position=tuple(red.center), size=tuple(red.size))
    grasp = targets.grasps(red_cup, TABLE_X[0])[0]
    lifted = kin.ik(geo.shifted(grasp.grasp, [0.0, 0.0, 0.10]))
    assert lifted is not None
    kin.set_arm(lifted)
    held = Held("red", Box(red.center + [0.0, 0.0, 0.10], red.size), kin.fk())
    kin.use(replace(kin.scene, joints={}, carried=Carried("red", held.box, held.tool_pose)))
    pairs = targets.place_relation("behind", blue, held.tool_pose, held, TABLE_TOP_Z)
    reachable = [i for i, (hover, _) in enumerate(pairs) if kin.ik(hover) is not None]
    assert reachable, "no heading or release point behind the blue cup is reachable"
    assert 0 not in reachable, "the grasp's own heading became reachable: this case no longer shows why turning helps"


def test_the_held_object_is_modelled_between_the_pads_and_not_below_its_support() -> None:
    """Perception saw the cup 2 cm off to the side and 1 cm low: the model sits where the closed fingers hold it."""
    seen = Box(SIDE_GRASP[:3] + [0.01, 0.02, -0.05], CUP)
    support = seen.bottom + 0.01
    held = targets.held_in_hand("cup", seen, SIDE_GRASP, support)
    fingers = geo.rotation_of(SIDE_GRASP).apply([0.0, 1.0, 0.0])
    assert abs(float(np.dot(held.box.center - SIDE_GRASP[:3], fingers))) < 1e-9
    assert held.box.bottom == pytest.approx(support)
    np.testing.assert_allclose(held.box.size, CUP)


def test_putting_down_tries_straight_below_first_then_spots_around() -> None:
    held = held_cup()
    pairs = targets.place_table(SIDE_GRASP, held, TABLE_TOP_Z)
    below = held.center_at(pairs[0][1])
    np.testing.assert_allclose(pairs[0][0], SIDE_GRASP)
    np.testing.assert_allclose(below[:2], held.box.center[:2], atol=1e-9)
    assert below[2] - CUP[2] / 2 == pytest.approx(TABLE_TOP_Z + geo.RELEASE_CLEARANCE)
    moved = [float(np.linalg.norm(held.center_at(release)[:2] - below[:2])) for _, release in pairs[1:]]
    assert np.all(np.diff(moved) > -1e-9) and max(moved) == pytest.approx(max(geo.DOWN_RINGS))
    assert all(hover[2] - release[2] == pytest.approx(targets.HOVER) for hover, release in pairs[1:])


def _object(oid: str, kind: str, center: list[float], size: list[float]) -> dict:
    return {"id": oid, "color": "white", "type": kind, "position": center, "size": size}


def test_what_a_cup_stands_on_is_modelled_below_it_even_when_seen_too_high() -> None:
    """From above only a plate's rim, or a box's sides, show around a cup on it: perception may place them too high."""
    scene = Scene()
    plate_top, box_top = TABLE_TOP_Z + 0.015, TABLE_TOP_Z + 0.06
    objects = [
        _object("cup", "cup", [0.63, 0.0, plate_top + 0.05], [0.07, 0.07, 0.10]),
        _object("plate", "plate", [0.63, 0.02, plate_top + 0.015], [0.16, 0.13, 0.015]),
        _object("saucer", "plate", [0.63, 0.30, TABLE_TOP_Z + 0.0075], [0.16, 0.16, 0.015]),
        _object("mug", "cup", [0.48, -0.2, box_top + 0.05], [0.07, 0.07, 0.10]),
        _object("box", "box", [0.47, -0.2, box_top - 0.01], [0.06, 0.06, 0.06]),  # seen 2 cm up
        _object("bowl", "bowl", [0.48, 0.2, TABLE_TOP_Z + 0.04], [0.14, 0.14, 0.08]),
        _object("egg", "cup", [0.48, 0.2, TABLE_TOP_Z + 0.055], [0.05, 0.05, 0.10]),
    ]
    scene.update_objects(perceived(objects), table_truth())
    boxes = scene.snapshot().obstacles()
    assert (boxes["plate"].bottom, boxes["plate"].top) == pytest.approx((TABLE_TOP_Z, plate_top))
    assert (boxes["box"].bottom, boxes["box"].top) == pytest.approx((TABLE_TOP_Z, box_top))
    assert boxes["cup"].bottom == pytest.approx(plate_top)
    np.testing.assert_allclose(boxes["saucer"].center, objects[2]["position"])  # nothing stands on it: as seen
    np.testing.assert_allclose(boxes["bowl"].center, objects[5]["position"])  # its walls stay around the egg


def test_a_cup_lifted_off_a_box_is_never_put_down_on_the_table_where_it_stood() -> None:
    """The executor remembers the footprint a cup was lifted off, for when perception loses the box under the hand."""
    stood = Box(np.array([0.48, 0.0, 0.83]), CUP)
    tool = geo.make_pose([0.48, 0.0, 0.95], geo.facing([1.0, 0.0, 0.0]))
    held = targets.held_in_hand("cup", stood, tool, support_top=0.78, lifted_off=stood)
    assert held.box.center[2] == pytest.approx(0.83)
    straight_down = geo.shifted(tool, [0.0, 0.0, -0.12])
    beside = geo.shifted(tool, [0.0, 0.12, -0.12])
    assert back_where_lifted(held, straight_down)
    assert not back_where_lifted(held, beside)
    from_the_table = targets.held_in_hand("cup", stood, tool, support_top=TABLE_TOP_Z)
    assert not back_where_lifted(from_the_table, straight_down)


def test_a_placement_past_the_tables_edge_is_never_a_free_spot() -> None:
    """In front of a cup by the edge facing the robot, the released cup would stand half off the table and fall."""
    scene = Scene()
    scene.update_objects(perceived([]), table_truth())
    snap = scene.snapshot()
    held = held_cup()
    near_edge = TABLE_X[0]
    for x, inside in ((near_edge + 0.10, True), (near_edge + CUP[0] / 2 + 0.01, False), (near_edge, False)):
        release = geo.shifted(held.tool_pose, [x - held.box.center[0], 0.0, 0.0])
        assert on_the_table(held, release, snap) is inside, x
    assert snap.table is not None
    assert not snap.table.holds(np.array([TABLE_X[1], 0.0]), CUP[:2] / 2)  # the far edge alike


def test_in_front_of_a_cup_near_the_tables_edge_the_cup_goes_closer_to_it() -> None:
    """15 cm from the edge facing the robot, a cup 5 cm in front of the landmark would stand off the table."""
    scene = Scene()
    scene.update_objects(perceived([]), table_truth())
    snap = scene.snapshot()
    held, landmark = held_cup(), standing(TABLE_X[0] + 0.15, 0.0)
    pairs = targets.place_relation("in_front_of", landmark, held.tool_pose, held, TABLE_TOP_Z)
    on_table = [release for _, release in pairs if on_the_table(held, release, snap)]
    assert on_table, "no spot in front of the cup on the table"
    for release in on_table:
        gap = landmark.center[0] - landmark.half[0] - (held.center_at(release)[0] + CUP[0] / 2)
        assert gap == pytest.approx(geo.CLOSE_GAP, abs=1e-6)


@pytest.mark.parametrize("relation", ["left_of", "right_of", "in_front_of", "behind"])
def test_the_second_try_beside_a_landmark_swings_the_hand_slides_along_or_goes_further_out_but_stays_beside_it(
    relation: str,
) -> None:
    landmark, held = standing(0.60, 0.05), held_cup()
    outward = {"left_of": [0, 1], "right_of": [0, -1], "in_front_of": [-1, 0], "behind": [1, 0]}[relation]
    along = [-outward[1], outward[0]]
    gaps, offsets, headings = [], [], set()
    for _, release in targets.place_relation_wider(relation, landmark, held.tool_pose, held, TABLE_TOP_Z):
        center = held.center_at(release)
        gaps.append(float(np.dot(center[:2] - landmark.center[:2], outward)) - landmark.half[0] - CUP[0] / 2)
        offsets.append(abs(float(np.dot(center[:2] - landmark.center[:2], along))))
        headings.add(round(float(np.dot(geo.approach_axis(release)[:2], outward)), 2))
    assert min(gaps) >= geo.CLOSE_GAP - 1e-6
    assert max(gaps) <= geo.GAP + targets.WIDER + geo.PLACE_SHIFT + 1e-6 <= 0.10 + 1e-6  # still beside it
    assert any(gap >= geo.GAP + targets.WIDER - 1e-6 for gap in gaps)
    assert max(offsets) == pytest.approx(targets.ALONG) and targets.ALONG <= 0.05  # slid along, not past it
    # the hand comes at the spot from every side, the landmark's own included
    assert min(headings) < -0.9 and max(headings) > 0.9


def test_a_square_box_off_to_the_side_is_squeezed_across_its_own_sides() -> None:
    """A 7 cm box 30 cm right: 9.4 cm across at the heading from the robot, 7 cm across its sides."""
    box = standing(0.61, -0.30, np.array([0.07, 0.07, 0.074]))
    grasps = geo.grasp_candidates(box)
    squeezed = []
    for grasp in grasps:
        rotation = geo.rotation_of(grasp.grasp)
        fingers = rotation.apply([0.0, 1.0, 0.0])
        squeezed.append(abs(fingers[0]) * box.size[0] + abs(fingers[1]) * box.size[1])
    assert max(squeezed) <= geo.MAX_GRIP_WIDTH + 1e-9  # every grasp offered fits the open gripper
    assert min(squeezed) == pytest.approx(0.07)
    headings = {
        tuple(np.round(geo.approach_axis(g.grasp)[:2], 2)) for g in grasps if abs(geo.approach_axis(g.grasp)[2]) < 0.1
    }
    assert {(1.0, 0.0), (0.0, 1.0), (0.0, -1.0)} <= headings  # from the front and from either side
    tops = [g for g in grasps if geo.approach_axis(g.grasp)[2] < -0.99]
    assert len(tops) >= 2  # from above, fingers across either pair of sides
