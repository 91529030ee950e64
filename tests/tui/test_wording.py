"""How objects read in the panels, and what the input line completes."""

from __future__ import annotations

import pytest

from shared.messages import PerceivedObject
from tui.command_input import VocabularySuggester
from tui.world import object_rgb, reach_text, size_text

pytestmark = pytest.mark.unit


def seen(**fields: object) -> PerceivedObject:
    """A perceived object with these fields (a cup's place and size unless given)."""
    return PerceivedObject(**{"id": "obj0", "position": (0.6, 0.0, 0.77), "size": (0.07, 0.07, 0.1), **fields})


@pytest.mark.parametrize(
    ("obj", "reach", "expected"),
    [
        ({}, {"right": {"pick_up": True}, "left": {"pick_up": True}}, "both"),
        ({}, {"right": {"pick_up": True}, "left": {"pick_up": False}}, "right"),
        ({}, {"right": {"pick_up": False}, "left": {"above": True}}, "left"),
        ({}, {"right": {"pick_up": False}, "left": {"pick_up": False}}, "none"),
        ({}, None, "?"),
        ({"held_by": "left"}, {"right": {"pick_up": True}}, "held (left)"),
    ],
)
def test_reach_wording(obj: dict, reach: dict | None, expected: str) -> None:
    assert reach_text(seen(**obj), reach) == expected


@pytest.mark.parametrize(
    ("size", "expected"),
    [
        ([0.07, 0.07, 0.1], "7×7×10 cm"),
        ([0.184, 0.18, 0.021], "18×18×2 cm"),
    ],
)
def test_size_wording(size: list[float], expected: str) -> None:
    assert size_text(size) == expected


@pytest.mark.parametrize(
    ("obj", "expected"),
    [
        ({"rgb": [200.0, 30.0, 30.0], "color": "blue"}, (200, 30, 30)),
        ({"rgb": [1.0, 0.5, 0.0]}, (255, 127, 0)),
        ({"color": "green"}, (26, 166, 38)),  # as the simulator paints green
        ({"color": "chartreuse"}, (160, 160, 160)),
    ],
)
def test_swatch_colour_prefers_the_measured_colour(obj: dict, expected: tuple[int, int, int]) -> None:
    assert object_rgb(seen(**obj)) == expected


@pytest.mark.parametrize(
    ("typed", "expected"),
    [
        ("mo", "move your right hand"),
        ("move your right hand above the r", "move your right hand above the red cup"),
        ("pi", "pick"),
        ("pick it u", "pick it up"),
        ("pick ", None),
        ("", None),
        ("zz", None),
    ],
)
def test_completion(typed: str, expected: str | None) -> None:
    suggester = VocabularySuggester()
    suggester.learn(["move", "pick", "up", "place"], ["move your right hand", "the red cup"])
    assert suggester.complete(typed) == expected
