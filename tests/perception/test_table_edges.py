"""The table's extent and edges, measured from its points (synthetic clouds with exact truth)."""

from __future__ import annotations

import pytest

from services.perception.pipeline import detect
from services.perception.synthetic import Box, Camera, Scene, render
from services.perception.table_edges import widest

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


def test_an_edge_hidden_for_a_while_stays_where_it_was_seen() -> None:
    """Something held up in front of the camera (an arm with a cup) hides the near part of the table.

    In that view alone the near edge seems to lie where the shadow begins;
    the table as seen so far keeps it where it was seen before.
    """
    table = dict(table_x=(0.45, 1.05), table_y=(-0.30, 0.35))
    clear = detect(render(Scene([CUP], **table))).table_extent
    held_up = Box((0.55, 0.0, 1.00), (0.14, 0.70, 0.04), "grey")
    hidden = detect(render(Scene([CUP, held_up], **table))).table_extent
    assert hidden.bounds[0, 0] > 0.47, "the occluder should hide the near edge in this view"
    kept = widest(clear, hidden)
    assert kept.edges["near"] == pytest.approx(0.45, abs=0.004)
    assert kept.bounds[0, 0] == pytest.approx(clear.bounds[0, 0])
    assert widest(None, hidden) is hidden


def test_a_shadows_rim_well_inside_the_table_seen_is_no_edge() -> None:
    """An arm reaching out low in front of the camera hides part of a table that runs out of view to the sides:
    in that view a side edge seems to lie where its shadow ends, but the table was seen running on past it;
    no side edge is kept."""
    clear = detect(render(Scene([CUP], table_x=(0.45, 1.05)))).table_extent
    assert set(clear.edges) == {"near", "far"}
    arm = Box((0.75, 0.20, 0.90), (0.70, 0.34, 0.06), "grey")
    hidden = detect(render(Scene([CUP, arm], table_x=(0.45, 1.05)))).table_extent
    assert hidden.edges.get("right", -1.0) > -0.1, "the arm should make a false right edge in this view"
    kept = widest(clear, hidden)
    assert set(kept.edges) == {"near", "far"}
