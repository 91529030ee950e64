"""Accuracy on every shipped scene, judged against the simulator's ground truth.

The scene is built in-process with the simulator's own library (same SAPIEN
scene, camera and cloud conversion as ``hfpbd sim``), rendered once per scene.
"""

from __future__ import annotations

import numpy as np
import pytest

from services.perception.evaluate import Score, score
from services.perception.pipeline import detect

sim_world = pytest.importorskip("services.sim.world", reason="the simulator library is not available")
from services.sim.cloud import cloud_message  # noqa: E402
from services.sim.layout import TABLE_TOP_Z  # noqa: E402
from services.sim.scene_file import available_scenes, load_scene, with_positions  # noqa: E402
from shared.messages import SimState, as_received  # noqa: E402

SCENES = available_scenes()


def sim_state(world) -> SimState:
    """The world's ``sim/state`` as perception's subscription hands it over."""
    state = as_received("sim_state", {"stamp": 0.0, **world.state()})
    assert isinstance(state, SimState)
    return state


# Two cups whose walls are 1 cm apart (the cups are 7.2 cm across at the rim).
APART = 0.072 + 0.01
CLOSE_PAIRS = {
    "side-by-side": {"obj0": [0.55, -APART / 2], "obj1": [0.55, APART / 2]},
    "one-behind": {"obj0": [0.50, 0.0], "obj1": [0.50 + APART, 0.0]},
    "diagonal": {"obj0": [0.52, -APART / 2.83], "obj1": [0.52 + APART / 1.414, APART / 2.83]},
}


@pytest.fixture(scope="module")
def world():
    return sim_world.SimWorld()


def observe(world, scene) -> Score:
    world.load(scene)
    world.settle(0.5)
    message = as_received("cloud", cloud_message(world.capture(), world.sim_time))
    return score(detect(message, sim_state(world)).objects, world.truth())


@pytest.fixture(scope="module")
def scores(world) -> dict[str, Score]:
    return {name: observe(world, load_scene(name)) for name in SCENES}


@pytest.mark.parametrize("scene", SCENES)
def test_all_objects_found_no_phantoms_and_right_words(scores, scene):
    result = scores[scene]
    assert result.missed == [] and result.phantoms == 0, f"missed {result.missed}, {result.phantoms} phantoms"
    assert result.wrong_words == []


def test_centre_and_size_errors_over_all_scenes(scores):
    total = Score()
    for result in scores.values():
        total.add(result)
    assert total.p95(total.centre_errors) <= 0.01
    assert total.p95(total.size_errors) <= 0.015


@pytest.mark.parametrize("placement", sorted(CLOSE_PAIRS))
def test_cups_one_centimetre_apart_are_two_objects(world, placement):
    result = observe(world, with_positions(load_scene("refexp_2_cups"), CLOSE_PAIRS[placement]))
    assert result.found == 2 and result.phantoms == 0
    assert max(result.centre_errors) <= 0.01


# A cup put on the default table's plate (1.5 cm high) or green box (6 cm): it touches what it stands on.
CUP_HALF = 0.05
ON_TOP = {
    "red cup on the plate": {"obj0": [0.63, 0.0, TABLE_TOP_Z + 0.015 + CUP_HALF]},
    "red cup off-centre on the plate": {"obj0": [0.66, 0.03, TABLE_TOP_Z + 0.015 + CUP_HALF]},
    "blue cup on the box": {"obj1": [0.48, 0.0, TABLE_TOP_Z + 0.06 + CUP_HALF]},
}


@pytest.mark.parametrize("placement", sorted(ON_TOP))
def test_a_cup_standing_on_another_object_is_seen_apart_from_it(world, placement):
    scene = with_positions(load_scene("default"), ON_TOP[placement])
    world.load(scene)
    world.settle(0.5)
    message = as_received("cloud", cloud_message(world.capture(), world.sim_time))
    detected = detect(message, sim_state(world)).objects
    cup_id = next(iter(ON_TOP[placement]))
    cup = next(t for t in world.truth() if t["id"] == cup_id)
    seen = [d for d in detected if (d.color, d.type) == (cup["color"], "cup")]
    assert len(seen) == 1, [(d.color, d.type) for d in detected]
    assert np.linalg.norm(seen[0].position - np.asarray(cup["position"])) <= 0.01
    assert abs(seen[0].size[2] - cup["size"][2]) <= 0.015, "the cup took in what it stands on"
    words = sorted((d.color, d.type) for d in detected)
    assert words == sorted((t["color"], t["type"]) for t in world.truth()), "an object vanished or was misnamed"
