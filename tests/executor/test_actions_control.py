"""Managing actions on screen: steps in words, deleting and moving a step, executing from a step."""

from __future__ import annotations

from pathlib import Path

import pytest

from services.executor.actions_control import apply, step_words
from services.executor.store import ActionStore, StoreError
from shared.messages import ActionList, ActionStarted, StepDeleted

pytestmark = pytest.mark.unit

LANDMARK = {"id": "obj0", "color": "red", "type": "cup", "size": [0.07, 0.07, 0.1], "position": [0.6, 0, 0.77]}
SAID = ["move your right hand above the red cup", "open your right hand", "pick it up"]


def _store(tmp_path: Path) -> ActionStore:
    store = ActionStore(tmp_path)
    store.create()
    for words in SAID:
        store.append_step({"procedure": "open", "args": {"arm": "right"}, "utterance": words})
    return store


def test_list_gives_every_step_in_the_users_words(tmp_path: Path) -> None:
    store = _store(tmp_path)
    store.create()
    store.append_step({"procedure": "pick_up", "args": {"arm": "left", "object": "obj0"}, "landmark": LANDMARK})
    reply = apply(store, {"op": "list"})
    assert isinstance(reply, ActionList)
    assert [a.words for a in reply.actions] == [SAID, ["pick up left the red cup"]]
    assert [a.steps for a in reply.actions] == [3, 1]


def test_a_step_without_words_never_shows_an_object_id(tmp_path: Path) -> None:
    words = step_words(
        {
            "procedure": "place_rel",
            "args": {"arm": "right", "relation": "next_to", "object": "obj3"},
            "landmark": {**LANDMARK, "id": "obj3", "color": "blue", "type": "box"},
        }
    )
    assert "obj3" not in words and "blue box" in words


def test_delete_step_removes_only_that_step_and_survives_a_restart(tmp_path: Path) -> None:
    store = _store(tmp_path)
    assert apply(store, {"op": "delete_step", "number": 1, "step": 2}) == StepDeleted(ok=True, number=1, steps=2)
    assert [s["utterance"] for s in ActionStore(tmp_path).get(1)["steps"]] == [SAID[0], SAID[2]]


@pytest.mark.parametrize("step, to, expected", [(3, 1, [2, 0, 1]), (1, 3, [1, 2, 0]), (2, 2, [0, 1, 2])])
def test_move_step_puts_it_at_the_new_place(tmp_path: Path, step: int, to: int, expected: list[int]) -> None:
    store = _store(tmp_path)
    apply(store, {"op": "move_step", "number": 1, "step": step, "to": to})
    assert [s["utterance"] for s in store.get(1)["steps"]] == [SAID[i] for i in expected]


@pytest.mark.parametrize(
    "request_, reason",
    [
        (
            {"op": "delete_step", "number": 1, "step": 4},
            "there is no step 4 in action 1: its steps are numbered 1 to 3",
        ),
        ({"op": "move_step", "number": 1, "step": 1, "to": 0}, "cannot move step 1 to 0: action 1 has steps 1 to 3"),
        ({"op": "move_step", "number": 1, "step": 1}, "needs a whole number for 'to', not None"),
        ({"op": "delete_step", "number": 2, "step": 1}, "there is no action 2: the actions are numbered 1 to 1"),
        ({"op": "execute", "number": 1, "step": 9}, "there is no step 9 in action 1"),
        ({"op": "undo_everything"}, "use list, show, rename, delete, delete_step, move_step or execute"),
    ],
)
def test_bad_requests_say_why_and_change_nothing(tmp_path: Path, request_: dict, reason: str) -> None:
    store = _store(tmp_path)
    with pytest.raises(StoreError, match=reason.replace("(", r"\(").replace(")", r"\)")):
        apply(store, request_, lambda number, step: (True, "accepted"))
    assert [s["utterance"] for s in ActionStore(tmp_path).get(1)["steps"]] == SAID


def test_execute_hands_the_action_and_step_to_the_runner(tmp_path: Path) -> None:
    store = _store(tmp_path)
    runs: list[tuple[int, int]] = []

    def run(number: int, step: int) -> tuple[bool, str]:
        runs.append((number, step))
        return True, "accepted"

    reply = apply(store, {"op": "execute", "number": 1, "step": 2}, run)
    assert runs == [(1, 2)] and reply == ActionStarted(ok=True, number=1, step=2, message="accepted")
    with pytest.raises(StoreError, match="still busy"):
        apply(store, {"op": "execute", "number": 1, "step": 1}, lambda n, s: (False, "I'm still busy with open"))
