"""Referring expressions: salient labels with margins, fewest words, compounds, round trips."""

from __future__ import annotations

import numpy as np
import pytest

from services.nlu.infer import Model
from services.nlu.language.refexp import Scene
from services.nlu.tokens import read
from services.nlu.world import parse_world
from tests.nlu.scenes import obj, random_scene, table_scene, world

pytestmark = pytest.mark.unit


def describe(scene: dict) -> dict[str, str]:
    return Model(parse_world(scene)).describe()


def test_default_scene_prefers_location_then_type() -> None:
    assert describe(table_scene()) == {
        "obj0": "the rightmost cup",
        "obj1": "the leftmost cup",
        "obj2": "the box",
        "obj3": "the plate",
    }


@pytest.mark.parametrize(
    "dy, expected",
    [
        (0.10, {"obj0": "the rightmost cup", "obj1": "the leftmost cup"}),  # beyond the 0.07 m margin
        (0.05, {"obj0": "the red cup", "obj1": "the blue cup"}),  # within it: colour decides
    ],
)
def test_location_label_needs_the_margin(dy: float, expected: dict[str, str]) -> None:
    scene = world(obj("obj0", "red", "cup", 0.6, -dy / 2), obj("obj1", "blue", "cup", 0.6, dy / 2))
    assert describe(scene) == expected


def test_size_then_height_then_colour() -> None:
    scene = world(
        obj("obj0", "red", "box", 0.6, 0.0, (0.15, 0.15, 0.10)),
        obj("obj1", "blue", "box", 0.62, 0.02, (0.05, 0.05, 0.10)),
    )
    assert describe(scene) == {"obj0": "the biggest box", "obj1": "the smallest box"}
    scene = world(
        obj("obj0", "red", "box", 0.6, 0.0, (0.08, 0.08, 0.18)),
        obj("obj1", "blue", "box", 0.62, 0.02, (0.08, 0.08, 0.11)),
    )
    assert describe(scene) == {"obj0": "the tallest box", "obj1": "the shortest box"}


def test_middle_of_three() -> None:
    scene = world(*(obj(f"obj{i}", "red", "cup", 0.6, y) for i, y in enumerate((-0.2, 0.0, 0.2))))
    assert describe(scene)["obj1"] == "the middle cup"


def test_compound_when_no_single_label_is_unique() -> None:
    grid = [(0.5, -0.15), (0.5, 0.15), (0.7, -0.15), (0.7, 0.15)]  # near/far x right/left, same everything
    scene = world(*(obj(f"obj{i}", "red", "cup", x, y) for i, (x, y) in enumerate(grid)))
    names = describe(scene)
    assert names["obj3"] == "the farthest leftmost cup"
    assert names["obj0"] == "the nearest rightmost cup"
    model = Model(parse_world(scene))
    assert max(model.ground("the far left cup").items(), key=lambda kv: kv[1])[0] == "obj3"


def test_labels_within_the_named_colour() -> None:
    scene = world(
        obj("obj0", "red", "cup", 0.6, 0.3), obj("obj1", "blue", "cup", 0.6, 0.1), obj("obj2", "blue", "cup", 0.6, -0.2)
    )
    grounding = Model(parse_world(scene)).ground("the leftmost blue cup")
    assert max(grounding, key=grounding.get) == "obj1"


def test_grounding_is_a_distribution_and_ambiguity_is_even() -> None:
    model = Model(parse_world(table_scene()))
    red = model.ground("the red cup")
    assert red["obj0"] > 0.9 and sum(red.values()) == pytest.approx(1.0, abs=1e-3)
    cups = model.ground("the cup")
    assert cups["obj0"] == pytest.approx(cups["obj1"]) and cups["obj0"] > 0.4


@pytest.mark.parametrize("seed", range(60))
def test_generated_expression_grounds_back(seed: int) -> None:
    """Paper IV-A: an object's own expression, used as input, refers to that object."""
    model = Model(parse_world(random_scene(seed)))
    scene: Scene = model.scene
    checked = 0
    for index, item in enumerate(model.world.objects):
        expression = scene.describe(index)
        if not expression.unique:
            continue
        probabilities = scene.ground(read(expression.text).terms)
        best = np.flatnonzero(probabilities == probabilities.max())
        assert list(best) == [index], f"{expression.text!r} meant {item.id}, got {probabilities.round(3)}"
        checked += 1
    assert checked >= 1 or len(set(describe(random_scene(seed)).values())) < model.scene.n
