"""Scene files: every shipped scene parses, random placement is seeded and clean, bad files are named."""

from __future__ import annotations

import itertools
import json
import math
from pathlib import Path

import pytest

from services.sim.layout import TABLE_TOP_Z
from services.sim.scene_file import SceneError, available_scenes, load_scene, parse_scene, randomized
from shared.colours import COLOURS

pytestmark = pytest.mark.unit

PAPER_SCENES = [
    "default",
    "task1_stack_cups",
    "task2_side_by_side",
    "task3_in_box",
    "task4_large_box",
    "task5_plate_edge",
]


def test_the_paper_scenes_ship() -> None:
    names = available_scenes()
    assert set(PAPER_SCENES) <= set(names)
    refexp = [n for n in names if n.startswith("refexp_")]
    assert {len(load_scene(n).objects) for n in refexp} == {2, 3, 4}


@pytest.mark.parametrize("name", available_scenes())
def test_scene_objects_rest_on_the_table_and_do_not_overlap(name: str) -> None:
    scene = load_scene(name)
    for spec in scene.objects:
        assert spec.position[2] == pytest.approx(TABLE_TOP_Z + spec.size[2] / 2)
        assert spec.color in COLOURS
    for a, b in itertools.combinations(scene.objects, 2):
        assert math.dist(a.position[:2], b.position[:2]) > a.footprint_radius * 0.7 + b.footprint_radius * 0.7


def test_default_scene_has_what_the_design_promises() -> None:
    kinds = {(s.color, s.type) for s in load_scene("default").objects}
    assert {("red", "cup"), ("blue", "cup"), ("green", "box")} <= kinds
    assert any(t == "plate" for _, t in kinds)


@pytest.mark.parametrize("seed", [0, 1, 7])
def test_random_placement_is_seeded_and_non_overlapping(seed: int) -> None:
    scene = load_scene("refexp_4_mixed")
    first, again = randomized(scene, seed), randomized(scene, seed)
    assert [s.position for s in first.objects] == [s.position for s in again.objects]
    assert [s.position for s in first.objects] != [s.position for s in scene.objects]
    for a, b in itertools.combinations(first.objects, 2):
        assert math.dist(a.position[:2], b.position[:2]) >= a.footprint_radius + b.footprint_radius
    for spec in first.objects:
        assert scene.region["x"][0] <= spec.position[0] <= scene.region["x"][1]


@pytest.mark.parametrize(
    "document, problem",
    [
        ({"objects": [{"type": "teapot", "color": "red", "size": [0.1, 0.1, 0.1], "position": [0.5, 0]}]}, "type"),
        ({"objects": [{"type": "cup", "color": "mauve", "size": [0.1, 0.1, 0.1], "position": [0.5, 0]}]}, "color"),
        ({"objects": [{"type": "cup", "color": "red", "size": [0.1, 0.1], "position": [0.5, 0]}]}, "size"),
        ({"objects": [{"type": "cup", "color": "red", "size": [0.1, 0.1, 0.1], "position": [0.5, "x"]}]}, "position"),
        (
            {"objects": [{"type": "cup", "color": "red", "size": [0.1, 0.1, 0.1], "position": [0.5, 0], "mass": -1}]},
            "mass",
        ),
        ({"objects": "none"}, "objects"),
    ],
)
def test_bad_scene_documents_name_the_problem(document: dict, problem: str) -> None:
    with pytest.raises(SceneError, match=problem):
        parse_scene(document, source="bad.json")


def test_unknown_scene_and_broken_file_are_reported(tmp_path: Path) -> None:
    with pytest.raises(SceneError, match="unknown scene 'kitchen'"):
        load_scene("kitchen")
    broken = tmp_path / "broken.json"
    broken.write_text("{not json")
    with pytest.raises(SceneError, match="cannot read scene"):
        load_scene(str(broken))
    json.loads((Path(__file__).parents[2] / "services/sim/scenes/default.json").read_text())
