"""The perception pipeline on ray-cast synthetic clouds with exact ground truth."""

from __future__ import annotations

import msgspec
import numpy as np
import pytest

from services.perception.cloud import CloudError
from services.perception.pipeline import detect
from services.perception.synthetic import Box, Camera, Cylinder, Scene, reaching_arm, render
from shared.colours import COLOURS
from shared.messages import Cloud

pytestmark = pytest.mark.unit

SMALL = Camera(width=320, height=240)


def mixed_scene(table_height: float = 0.75) -> Scene:
    z = table_height
    return Scene(
        [
            Cylinder((0.70, -0.12, z + 0.05), 0.035, 0.10, "red", wall=0.005),
            Cylinder((0.72, 0.02, z + 0.055), 0.04, 0.11, "blue"),
            Box((0.85, 0.20, z + 0.03), (0.12, 0.08, 0.06), "green", yaw=0.4),
            Cylinder((0.95, -0.05, z + 0.01), 0.10, 0.02, "white", kind="plate"),
            Cylinder((0.80, 0.42, z + 0.035), 0.07, 0.07, "yellow", wall=0.006, kind="bowl"),
        ],
        table_height=table_height,
    )


def match_truth(detected: list, truth: list[dict]) -> list[tuple[dict, object]]:
    """Pair each true object with the nearest detection (each used once)."""
    pairs, free = [], list(detected)
    for item in truth:
        nearest = min(free, key=lambda d: np.linalg.norm(d.position - item["position"]))
        free.remove(nearest)
        pairs.append((item, nearest))
    return pairs


@pytest.fixture(scope="module")
def mixed() -> tuple[Scene, dict]:
    scene = mixed_scene()
    return scene, render(scene, noise=0.001, seed=3)


def test_every_object_found_without_phantoms(mixed):
    scene, cloud = mixed
    assert len(detect(cloud).objects) == len(scene.objects)


def test_positions_and_sizes_match_ground_truth(mixed):
    scene, cloud = mixed
    pairs = match_truth(detect(cloud).objects, scene.truth())
    centre_err = [np.linalg.norm(d.position - t["position"]) for t, d in pairs]
    size_err = np.concatenate([np.abs(d.size - t["size"]) for t, d in pairs])
    assert max(centre_err) <= 0.01, centre_err
    assert size_err.max() <= 0.015, size_err


def test_colour_and_type_words_match_ground_truth(mixed):
    scene, cloud = mixed
    pairs = match_truth(detect(cloud).objects, scene.truth())
    assert [(d.color, d.type) for _, d in pairs] == [(t["color"], t["type"]) for t, _ in pairs]


@pytest.mark.parametrize("table_height", [0.55, 0.72])
def test_table_found_at_its_height_not_the_floor(table_height):
    cloud = render(mixed_scene(table_height), SMALL)
    plane = detect(cloud).plane
    assert plane.z_at(0.8, 0.0) == pytest.approx(table_height, abs=0.003)


@pytest.mark.parametrize("colour", sorted(COLOURS))
def test_colour_word(colour):
    cloud = render(Scene([Box((0.8, 0.0, 0.80), (0.08, 0.08, 0.10), colour)]), SMALL)
    (found,) = detect(cloud).objects
    assert found.color == colour


@pytest.mark.parametrize(
    "shape, word",
    [
        (Cylinder((0.8, 0.0, 0.80), 0.035, 0.10, "red", wall=0.005), "cup"),
        (Cylinder((0.8, 0.0, 0.81), 0.04, 0.12, "red"), "cup"),
        (Box((0.8, 0.0, 0.80), (0.08, 0.08, 0.10), "red"), "box"),
        (Box((0.8, 0.0, 0.78), (0.15, 0.06, 0.06), "red", yaw=0.7), "box"),
        (Cylinder((0.8, 0.0, 0.76), 0.11, 0.02, "red"), "plate"),
        (Cylinder((0.8, 0.0, 0.785), 0.08, 0.07, "red", wall=0.006), "bowl"),
    ],
)
def test_type_word(shape, word):
    (found,) = detect(render(Scene([shape]))).objects
    assert found.type == word


@pytest.mark.parametrize(
    "offset", [(0.0, 0.08), (0.08, 0.0), (0.0566, 0.0566)], ids=["side-by-side", "one-behind", "diagonal"]
)
def test_cups_one_centimetre_apart_are_separate(offset):
    a = (0.75, 0.0, 0.80)
    b = (a[0] + offset[0], a[1] + offset[1], 0.80)
    cloud = render(Scene([Cylinder(a, 0.035, 0.10, "red"), Cylinder(b, 0.035, 0.10, "red")]))
    found = detect(cloud).objects
    assert len(found) == 2
    assert sorted(round(float(np.linalg.norm(d.position[:2] - a[:2])), 2) for d in found) == [0.0, 0.08]


def test_oriented_box_reports_its_own_length_and_width():
    cloud = render(Scene([Box((0.8, 0.0, 0.78), (0.16, 0.06, 0.06), "green", yaw=0.6)]))
    (found,) = detect(cloud).objects
    assert found.box_size[:2] == pytest.approx([0.16, 0.06], abs=0.01)
    assert found.box_yaw == pytest.approx(0.6, abs=0.05)


def inside_some_object(position: np.ndarray, scene: Scene, margin: float = 0.01) -> bool:
    return any(
        all(abs(position[k] - t["position"][k]) <= t["size"][k] / 2 + margin for k in (0, 1)) for t in scene.truth()
    )


def test_arm_over_the_table_is_not_an_object():
    capsules, state = reaching_arm((0.65, -0.30, 0.90))
    scene = mixed_scene()
    scene.links = capsules
    cloud = render(scene, SMALL)
    masked = detect(cloud, state).objects
    assert len(masked) >= 3 and all(inside_some_object(d.position, scene) for d in masked)
    unmasked = detect(cloud).objects  # without the robot's state the arm would be a phantom
    assert not all(inside_some_object(d.position, scene) for d in unmasked)


@pytest.mark.parametrize("noise, dropout", [(0.002, 0.0), (0.0, 0.2)])
def test_noise_and_missing_returns_keep_every_object(noise, dropout):
    scene = mixed_scene()
    found = detect(render(scene, noise=noise, dropout=dropout, seed=7)).objects
    assert sorted(d.color for d in found) == sorted(o.colour for o in scene.objects)


def test_infinite_and_nan_points_are_ignored(mixed):
    scene, cloud = mixed
    xyz = cloud.xyz.copy()
    xyz[::7, ::5, 0] = np.inf
    xyz[1::9, ::3, 2] = -np.inf
    xyz[2::11, ::4, 1] = np.nan
    assert len(detect(msgspec.structs.replace(cloud, xyz=xyz)).objects) == len(scene.objects)


def cloud_with(xyz: np.ndarray, rgb: np.ndarray | None = None) -> Cloud:
    rgb = np.zeros(xyz.shape, np.uint8) if rgb is None else rgb
    return Cloud(stamp=0.0, xyz=xyz.astype(np.float32), rgb=rgb, camera_pose=(0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0))


@pytest.mark.parametrize(
    "cloud, reason",
    [
        (cloud_with(np.full((240, 320, 3), np.nan)), "point cloud is empty"),
        (cloud_with(np.zeros((0, 0, 3))), "point cloud is empty"),
        (cloud_with(np.zeros((240, 320))), "shape (H, W, 3)"),
        (cloud_with(np.zeros((4, 4, 3)), np.zeros((2, 2, 3), np.uint8)), "does not match"),
    ],
)
def test_unusable_cloud_is_a_clear_error(cloud, reason):
    with pytest.raises(CloudError, match=reason.replace("(", r"\(").replace(")", r"\)")):
        detect(cloud)


def test_a_wall_is_not_a_table():
    """A camera facing a wall sees only a vertical plane."""
    v, u = np.mgrid[0:240, 0:320] / 240.0
    wall = np.stack([np.full_like(u, 1.5), u - 0.6, 1.5 - v], axis=-1)
    with pytest.raises(CloudError, match="no table"):
        detect(cloud_with(wall))
