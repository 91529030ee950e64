"""The table's extent and edges, measured from its points (synthetic clouds with exact truth)."""

from __future__ import annotations

import pytest

from services.perception.pipeline import detect
from services.perception.synthetic import Box, Camera, Scene, render

pytestmark = pytest.mark.unit

CUP = Box((0.70, 0.0, 0.80), (0.10, 0.10, 0.10), "red")


@pytest.mark.parametrize("noise", [0.0, 0.002])
def test_every_edge_in_view_is_found_to_a_few_millimetres(noise: float) -> None:
    scene = Scene([CUP], table_x=(0.45, 1.05), table_y=(-0.30, 0.35))
    extent = detect(render(scene, noise=noise)).table_extent
    assert set(extent.edges) == {"near", "far", "right", "left"}
    for side, truth in {"near": 0.45, "far": 1.05, "right": -0.30, "left": 0.35}.items():
        assert extent.edges[side] == pytest.approx(truth, abs=0.004), side


def test_a_table_running_out_of_view_has_no_edge_on_that_side() -> None:
    """The default synthetic table is wider than the view: its sides are not edges, only limits of what was seen."""
    extent = detect(render(Scene([CUP]))).table_extent
    assert set(extent.edges) == {"near", "far"}
    assert extent.edges["near"] == pytest.approx(0.45, abs=0.004)
    assert -0.75 < extent.bounds[1, 0] < -0.3 and 0.3 < extent.bounds[1, 1] < 0.75


def test_an_object_over_the_near_edge_does_not_move_it() -> None:
    """A plate sticking out over the edge hides part of it; the edge stays where the rest of it is seen."""
    plate = Box((0.48, 0.05, 0.756), (0.22, 0.22, 0.012), "blue")
    extent = detect(render(Scene([plate], table_x=(0.45, 1.05)), Camera())).table_extent
    assert extent.edges["near"] == pytest.approx(0.45, abs=0.004)
