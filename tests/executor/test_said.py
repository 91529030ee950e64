"""On replay, the object found again is the one the user's words meant, and a replay asks when they no longer pick one."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from services.executor.executor import Executor
from services.executor.grounding import descriptor
from services.executor.referring import refer
from services.executor.said import SAID, UNIQUE_AS, find_again, remembered_words
from services.executor.store import ActionStore
from shared.messages import PerceivedObject
from tests.executor.test_skills import BLUE, PLATE_0, RED, SERVE
from tests.executor.test_skills_executor import TABLE, RecordingBus, command, replaying

pytestmark = pytest.mark.unit

CUP = (0.07, 0.07, 0.10)


def obj(oid: str, color: str, kind: str, x: float, y: float, size: tuple[float, float, float] = CUP) -> PerceivedObject:
    return PerceivedObject(id=oid, color=color, type=kind, size=size, position=(x, y, 0.8))


def taught(thing: PerceivedObject, **words: str) -> dict[str, object]:
    return {**descriptor(thing), **words}


# the robot's left is +y: "leftmost" is the largest y
LEFT_CUP_THEN = obj("t1", "red", "cup", 0.60, 0.25)
BOX = obj("box", "blue", "box", 0.75, 0.0, (0.12, 0.12, 0.16))


def test_the_leftmost_red_cup_is_found_again_as_the_leftmost_even_when_the_other_stands_where_it_stood() -> None:
    now = [obj("p", "red", "cup", 0.60, 0.24), obj("q", "red", "cup", 0.60, 0.35), BOX]
    found = find_again([taught(LEFT_CUP_THEN, said="leftmost red cup")], now)
    assert found.mapping == {"t1": "q"}
    assert not found.unsure


def test_words_that_no_longer_pick_one_object_are_asked_about() -> None:
    now = [obj("p", "red", "cup", 0.60, -0.2), obj("q", "red", "cup", 0.60, 0.2), BOX]
    found = find_again([taught(LEFT_CUP_THEN, said="red cup")], now)
    assert found.mapping == {}
    assert set(found.unsure["t1"].could_be) == {"p", "q"}
    assert found.unsure["t1"].words == "red cup"


def test_the_robots_own_words_then_decide_where_the_users_do_not() -> None:
    now = [obj("p", "red", "cup", 0.60, -0.2), obj("q", "red", "cup", 0.60, 0.2), BOX]
    found = find_again([taught(LEFT_CUP_THEN, said="red cup", unique_as="the leftmost red cup")], now)
    assert found.mapping == {"t1": "q"}


def test_it_names_nothing_so_the_look_alike_nearest_to_where_the_object_stood_is_taken() -> None:
    now = [obj("p", "red", "cup", 0.62, 0.22), obj("q", "red", "cup", 0.60, -0.25), BOX]
    found = find_again([taught(LEFT_CUP_THEN, said="it")], now)
    assert found.mapping == {"t1": "p"}
    assert not found.unsure


def test_a_landmark_named_once_and_then_called_it_keeps_the_words_that_named_it() -> None:
    first = taught(LEFT_CUP_THEN, said="it")
    later = taught(LEFT_CUP_THEN, said="leftmost red cup")
    now = [obj("p", "red", "cup", 0.60, 0.20), obj("q", "red", "cup", 0.60, 0.30), BOX]
    assert find_again([first, later], now).mapping == {"t1": "q"}


def test_an_object_without_look_alikes_is_matched_by_look_whatever_the_words() -> None:
    now = [obj("p", "red", "cup", 0.5, -0.3), obj("b2", "blue", "box", 0.7, 0.1, (0.12, 0.12, 0.16))]
    found = find_again([taught(LEFT_CUP_THEN, said="leftmost red cup"), taught(BOX, said="blue box")], now)
    assert found.mapping == {"t1": "p", "box": "b2"}


def test_a_relational_phrase_is_read_against_every_object_in_view() -> None:
    near_box = obj("p", "red", "cup", 0.75, 0.14)
    far = obj("q", "red", "cup", 0.45, -0.3)
    found = find_again([taught(LEFT_CUP_THEN, said="red cup next to the box")], [far, near_box, BOX])
    assert found.mapping == {"t1": "p"}


def test_a_step_keeps_the_users_object_words_and_the_robots() -> None:
    words = remembered_words({"verb": "pick up", "object": "leftmost red cup"}, "the red cup on the left")
    assert words == {SAID: "leftmost red cup", UNIQUE_AS: "the red cup on the left"}
    assert remembered_words({"verb": "open"}, None) == {}


def test_a_replay_whose_words_fit_two_objects_now_asks_which_before_anything_moves(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    bus = RecordingBus()
    executor = Executor(bus, ActionStore(tmp_path))  # type: ignore[arg-type]
    other_red = PerceivedObject(id="obj3", color="red", type="cup", size=CUP, position=(0.55, -0.25, 0.8))
    executor.scene.update_objects([RED, BLUE, PLATE_0, other_red], TABLE)
    executor.store.create()
    first, second = SERVE
    executor.store.append_step({**first, "landmark": {**first["landmark"], SAID: "red cup"}})
    executor.store.append_step(second)
    ran: list[tuple[str, dict[str, Any]]] = []
    replaying(executor, monkeypatch, ran)
    command(executor, "execute", {})
    snap = executor.scene.snapshot()
    assert [p for p, _ in ran] == ["record"]  # a look at the table, nothing else
    cups = [refer(snap.objects, "obj0"), refer(snap.objects, "obj3")]
    assert bus.said()[-1] == (
        "clarify",
        f"When you taught me action 1, \u201cred cup\u201d meant one object, but now it could be {cups[0]} or {cups[1]}."
        f" Which one do you mean? Say, for example, \u201cexecute it with {cups[0]}\u201d.",
    )
