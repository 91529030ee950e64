"""Re-finding an action's landmarks among the objects seen now."""

from __future__ import annotations

import pytest

from services.executor.grounding import descriptor, reground
from shared.messages import PerceivedObject

pytestmark = pytest.mark.unit


def obj(
    oid: str,
    color: str,
    kind: str,
    size: tuple[float, float, float],
    pos: tuple[float, float, float] = (0.6, 0.0, 0.77),
) -> PerceivedObject:
    return PerceivedObject(id=oid, color=color, type=kind, size=size, position=pos)


RED_CUP = obj("a", "red", "cup", (0.07, 0.07, 0.10))
BLUE_BOX = obj("b", "blue", "box", (0.12, 0.08, 0.06))


def test_landmarks_follow_their_descriptors_not_their_old_ids() -> None:
    now = [
        obj("obj7", "blue", "box", (0.12, 0.08, 0.06), (0.5, 0.3, 0.75)),
        obj("obj3", "red", "cup", (0.072, 0.069, 0.10), (0.7, -0.2, 0.77)),
    ]
    result = reground([descriptor(RED_CUP), descriptor(BLUE_BOX)], now)
    assert result.mapping == {"a": "obj3", "b": "obj7"}
    assert result.missing == {}


def test_two_alike_landmarks_get_two_different_objects() -> None:
    first, second = obj("a", "red", "cup", (0.07, 0.07, 0.1)), obj("b", "red", "cup", (0.07, 0.07, 0.1))
    now = [obj("x", "red", "cup", (0.07, 0.07, 0.1)), obj("y", "red", "cup", (0.07, 0.07, 0.1))]
    result = reground([descriptor(first), descriptor(second)], now)
    assert sorted(result.mapping.values()) == ["x", "y"]


@pytest.mark.parametrize(
    "now, words",
    [
        (
            [obj("x", "blue", "cup", (0.07, 0.07, 0.1))],
            "There is no red cup on the table any more (the closest I see is a blue cup).",
        ),
        (
            [obj("x", "red", "box", (0.07, 0.07, 0.1))],
            "There is no red cup on the table any more (the closest I see is a red box).",
        ),
        (
            [obj("x", "red", "cup", (0.20, 0.20, 0.3))],
            "There is no red cup of the size I was taught on the table any more",
        ),
        ([], "I can't see any objects, so I can't find the red cup."),
    ],
)
def test_too_different_objects_are_rejected_naming_what_is_missing(now: list[dict], words: str) -> None:
    result = reground([descriptor(RED_CUP)], now)
    assert result.mapping == {}
    assert result.missing["a"].startswith(words)


def test_one_object_cannot_stand_for_two_landmarks() -> None:
    first, second = obj("a", "red", "cup", (0.07, 0.07, 0.1)), obj("b", "red", "cup", (0.07, 0.07, 0.1))
    result = reground([descriptor(first), descriptor(second)], [obj("x", "red", "cup", (0.07, 0.07, 0.1))])
    assert list(result.mapping.values()) == ["x"]
    assert "only find one red cup" in next(iter(result.missing.values()))


def test_a_missing_type_word_still_matches_but_costs_more() -> None:
    now = [obj("x", "red", "unknown", (0.07, 0.07, 0.1)), obj("y", "red", "cup", (0.08, 0.08, 0.11))]
    assert reground([descriptor(RED_CUP)], now).mapping == {"a": "y"}
    assert reground([descriptor(RED_CUP)], now[:1]).mapping == {"a": "x"}


def test_an_unknown_colour_is_no_match_for_a_known_one() -> None:
    assert reground([descriptor(RED_CUP)], [obj("x", "unknown", "cup", (0.07, 0.07, 0.1))]).mapping == {}
