"""The executor's handling of the skills commands where nothing has to move: naming, switching, refusals.

The executor runs here on a bus that only records what is published and
answers no request: a command that would reach the simulator or perception
shows up as a request, so "nothing moved" is checked, not assumed.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import msgspec
import numpy as np
import pytest

from services.executor.commands import Step, check
from services.executor.executor import Executor
from services.executor.geometry import Box
from services.executor.procedures import StepFailed
from services.executor.referring import refer
from services.executor.store import ActionStore
from services.executor.targets import Held
from shared import messages
from shared.bus import BusTimeout
from shared.keys import Keys
from shared.messages import ExecutorState, PerceivedObject, typed
from tests.executor.test_skills import BLUE, CUP, PLATE_0, RED, SERVE, TABLE_Z, desc

pytestmark = pytest.mark.unit


TABLE = messages.Table(height=TABLE_Z, extent=messages.TableExtent(x=(0.3, 1.1), y=(-0.6, 0.6)))


class RecordingBus:
    """Enough of :class:`shared.bus.Bus` for an executor that is not started: it keeps what is published."""

    def __init__(self) -> None:
        self.keys = Keys("skills-test")
        self.published: list[tuple[str, Any]] = []
        self.requests: list[str] = []

    def subscribe(self, *args: Any, **kwargs: Any) -> None:
        pass

    def watch_alive(self, *args: Any) -> None:
        pass

    def publisher(self, key: str, **kwargs: Any) -> RecordingBus.Publisher:
        return RecordingBus.Publisher(self, key)

    def publish(self, key: str, message: Any) -> None:
        self.published.append((key, msgspec.to_builtins(message)))  # as a subscriber without a schema reads it

    def request(self, key: str, *args: Any, **kwargs: Any) -> Any:
        self.requests.append(key)
        raise BusTimeout(f"nothing answers {key} here")

    def alive_services(self, timeout: float = 0.0) -> set[str]:
        return set()

    class Publisher:
        def __init__(self, bus: RecordingBus, key: str) -> None:
            self.bus, self.key = bus, key

        def put(self, message: Any) -> None:
            self.bus.publish(self.key, message)

    def said(self) -> list[tuple[str, str]]:
        return [(m["kind"], m["text"]) for k, m in self.published if k == self.keys.say]

    def states(self) -> list[dict[str, Any]]:
        return [m for k, m in self.published if k == self.keys.executor_state]


@pytest.fixture
def robot(tmp_path: Path) -> tuple[Executor, RecordingBus]:
    """An executor whose threads are never started: commands run on the test's thread."""
    bus = RecordingBus()
    executor = Executor(bus, ActionStore(tmp_path))  # type: ignore[arg-type]
    executor.scene.update_objects([RED, BLUE, PLATE_0], TABLE)
    return executor, bus


def command(executor: Executor, procedure: str, args: dict[str, Any]) -> None:
    """Run one checked command on the calling thread, as the command worker would."""
    executor.worker.run([Step(procedure, check(procedure, args), {}, "")], "")


def taught(executor: Executor, *names: str | None) -> None:
    """Actions with the serve steps, named ``names`` (None: left unnamed)."""
    for name in names:
        number = executor.store.create()
        for step in SERVE:
            executor.store.append_step(step)
        if name:
            executor.store.rename(number, name)


def test_naming_the_current_action_is_said_persisted_and_published(robot: tuple[Executor, RecordingBus]) -> None:
    executor, bus = robot
    taught(executor, None, None)
    command(executor, "name_action", {"name": "serve"})
    command(executor, "name_action", {"name": "tidy up", "action": 1})
    assert bus.said() == [
        ("info", "Action 2 is now called \u201cserve\u201d."),
        ("info", "Action 1 is now called \u201ctidy up\u201d."),
    ]
    assert [(a["name"], a["number"]) for a in executor.store.summaries()] == [("tidy up", 1), ("serve", 2)]
    executor.publish_state()
    state = typed("executor_state", bus.states()[-1])
    assert isinstance(state, ExecutorState)
    assert [(s.name, s.action) for s in state.skills] == [("tidy up", 1), ("serve", 2)]


@pytest.mark.parametrize(
    "args, sentence",
    [
        ({"name": "serve", "action": 1}, "Action 2 is already called \u201cserve\u201d"),
        ({"name": "pick up"}, "\u201cpick up\u201d is already one of my commands"),
        ({"name": "wave", "action": 7}, "There is no action 7 to name; the actions are 1 and 2 (\u201cserve\u201d)."),
    ],
)
def test_a_name_that_cannot_be_given_is_refused_with_the_reason(
    robot: tuple[Executor, RecordingBus], args: dict[str, Any], sentence: str
) -> None:
    executor, bus = robot
    taught(executor, None, "serve")
    command(executor, "name_action", args)
    assert len(bus.said()) == 1 and bus.said()[0][0] == "error" and sentence in bus.said()[0][1]
    assert [a["name"] for a in executor.store.summaries()] == [None, "serve"]


def test_naming_with_no_action_says_so(robot: tuple[Executor, RecordingBus]) -> None:
    executor, bus = robot
    command(executor, "name_action", {"name": "serve"})
    assert bus.said() == [("error", "There is no action to name yet; teach me some steps first.")]


def test_a_switch_to_an_action_that_does_not_exist_lists_the_actions(robot: tuple[Executor, RecordingBus]) -> None:
    executor, bus = robot
    taught(executor, "serve", None)
    command(executor, "switch_action", {"target": 99})
    assert bus.said() == [("error", "There is no action 99; the actions are 1 (\u201cserve\u201d) and 2.")]
    assert executor.store.current == 2


def test_a_stored_step_that_fails_the_check_stops_a_replay_before_anything_moves(
    robot: tuple[Executor, RecordingBus],
) -> None:
    executor, bus = robot
    taught(executor, None)
    executor.store.append_step({"procedure": "place_rel", "args": {"arm": "right", "relation": "under", "object": "x"}})
    command(executor, "execute", {})
    assert bus.said() == [
        (
            "error",
            "Step 3 of action 1 is not a step I can run: 'under' is not a relation I know; I know above, next_to, "
            "left_of, right_of, in_front_of, behind, on_top_of, near. I won't run action 1.",
        )
    ]
    assert bus.requests == []  # not even a look at the table


@pytest.mark.parametrize(
    "args, sentence",
    [
        (
            {"skill": "fetch"},
            "I don't know an action called \u201cfetch\u201d; the actions with names are \u201cserve\u201d.",
        ),
        ({"skill": 4}, "There is no action 4; the actions are 1 (\u201cserve\u201d) and 2."),
        ({"skill": 2, "objects": {"carried": "obj1"}}, "Action 2 has no steps yet."),
        (
            {"skill": "serve", "objects": {"carried": "obj9"}},
            "I can't see that object on the table now.",
        ),
        (
            {"skill": "serve", "objects": {"carried": "obj1"}, "each": ["obj0", "obj1"]},
            "Tell me either the one object to carry or the objects to do it for one by one, not both.",
        ),
    ],
)
def test_a_skill_that_cannot_run_is_refused_before_anything_moves(
    robot: tuple[Executor, RecordingBus], args: dict[str, Any], sentence: str
) -> None:
    executor, bus = robot
    taught(executor, "serve")
    executor.store.create()
    command(executor, "run_skill", args)
    assert bus.said() == [("error", sentence)]
    assert bus.requests == []
    assert executor.store.step_counts() == [2, 0]  # nothing recorded


def test_a_skill_without_a_landmark_refuses_one(robot: tuple[Executor, RecordingBus]) -> None:
    executor, bus = robot
    number = executor.store.create()
    executor.store.append_step(SERVE[0])
    executor.store.rename(number, "lift")
    command(executor, "run_skill", {"skill": "lift", "objects": {"landmark": "obj2"}})
    assert bus.said() == [
        ("error", "\u201clift\u201d never places anything relative to another object, so I can't give it one.")
    ]


def test_putting_back_is_refused_for_an_empty_hand_and_an_object_never_moved(
    robot: tuple[Executor, RecordingBus],
) -> None:
    executor, bus = robot
    command(executor, "place_back", {"arm": "left"})
    assert bus.said() == [("error", "My left hand isn't holding anything to put back.")]
    snap = executor.scene.snapshot()
    executor.procedures.set_held("right", Held("obj0", Box.of(RED), np.zeros(7), seen_as=RED))
    with pytest.raises(StepFailed) as caught:
        executor.steps.origin({"arm": "right"}, snap)
    assert str(caught.value) == (
        f"I haven't moved {refer(snap.objects, 'obj0')} from anywhere else since I started, so I don't know "
        "where it was before; tell me where to put it."
    )
    with pytest.raises(StepFailed, match="My right hand is holding .*, not "):
        executor.steps.origin({"arm": "right", "object": "obj1"}, snap)
    executor.origins.picked(RED, snap.objects)
    assert executor.steps.origin({"arm": "right", "object": "obj0"}, snap) == ("obj0", {"center": list(RED.position)})


def replaying(executor: Executor, monkeypatch: pytest.MonkeyPatch, ran: list[tuple[str, dict[str, Any]]]) -> None:
    """Steps "run" by noting them (the arms stay), and a fresh look sees the scene as it is set in the test."""

    def step(procedure: str, args: dict[str, Any], *rest: Any, **kwargs: Any) -> bool:
        ran.append((procedure, args))
        return True

    monkeypatch.setattr(executor.steps, "run", step)
    monkeypatch.setattr(executor.perception, "record", lambda: list(executor.scene.snapshot().objects.values()))


def test_a_replayed_step_whose_effect_does_not_hold_stops_the_replay_saying_what_differs(
    robot: tuple[Executor, RecordingBus], monkeypatch: pytest.MonkeyPatch
) -> None:
    executor, bus = robot
    taught(executor, None)
    ran: list[tuple[str, dict[str, Any]]] = []
    replaying(executor, monkeypatch, ran)
    command(executor, "execute", {})  # the hand "picked up" the cup but holds nothing
    snap = executor.scene.snapshot()
    assert [p for p, _ in ran] == ["record", "pick_up"]  # the placement after it never ran
    assert bus.said()[-1] == (
        "error",
        f"My right hand is empty after picking up {refer(snap.objects, 'obj0')}. I stopped action 1 after step 1 of 2;"
        " I won't go on with \u201cput it on the plate\u201d.",
    )


def test_a_skill_runs_with_the_objects_said_and_is_recorded_in_another_action_as_one_step(
    robot: tuple[Executor, RecordingBus], monkeypatch: pytest.MonkeyPatch
) -> None:
    executor, bus = robot
    taught(executor, "serve")
    executor.store.create()
    runs: list[tuple[int, dict[str, str] | None]] = []

    def replay(number: int, name: str, start: int = 1, **kwargs: Any) -> bool:
        runs.append((number, kwargs.get("bound")))
        return True

    monkeypatch.setattr(executor.replay, "replay", replay)
    executor.worker.run(
        [Step("run_skill", {"skill": "serve", "objects": {"carried": "obj1"}}, {}, "serve the blue cup")],
        "serve the blue cup",
    )
    assert runs == [(1, {"carried": "obj1", "landmark": "obj2"})]  # the landmark it was taught with, found again
    step = executor.store.get(2)["steps"][0]
    assert step["procedure"] == "run_skill" and step["args"] == {"skill": "serve", "objects": {"carried": "obj1"}}
    assert step["bound"]["carried"]["color"] == "blue" and step["bound"]["landmark"]["type"] == "plate"
    assert step["utterance"] == "serve the blue cup"

    executor.store.switch(1)  # "execute it with the blue cup" while on the skill itself: a replay, not a step
    command(executor, "run_skill", {"skill": 1, "objects": {"carried": "obj1"}})
    assert executor.store.step_counts() == [2, 1] and bus.said() == []


def test_each_object_gets_its_own_run_in_the_order_said_and_the_first_failure_ends_the_rest(
    robot: tuple[Executor, RecordingBus], monkeypatch: pytest.MonkeyPatch
) -> None:
    executor, bus = robot
    taught(executor, "serve")
    runs: list[dict[str, str]] = []

    def replay(number: int, name: str, start: int = 1, **kwargs: Any) -> bool:
        runs.append(kwargs["bound"])
        return len(runs) < 2  # the second run fails (it says why itself)

    monkeypatch.setattr(executor.replay, "replay", replay)
    third = PerceivedObject(id="obj3", color="green", type="cup", position=(0.45, 0.0, 0.80), size=CUP)
    executor.scene.update_objects([RED, BLUE, PLATE_0, third])
    snap = executor.scene.snapshot()
    command(executor, "run_skill", {"skill": "serve", "each": ["obj1", "obj0", "obj3"]})
    assert [run["carried"] for run in runs] == ["obj1", "obj0"]
    blue, red, green = (refer(snap.objects, oid) for oid in ("obj1", "obj0", "obj3"))
    assert bus.said()[0] == ("narration", f"I'll run \u201cserve\u201d with {blue}, then {red}, then {green}.")
    assert bus.said()[-1] == (
        "error",
        f"I ran \u201cserve\u201d with {blue}; I didn't finish it with {red} and {green}.",
    )


def test_an_action_that_calls_a_skill_replays_it_with_the_objects_it_was_called_with(
    robot: tuple[Executor, RecordingBus], monkeypatch: pytest.MonkeyPatch
) -> None:
    executor, bus = robot
    taught(executor, "serve")
    blue = {"id": "old1", "color": "blue", "type": "cup", "size": list(CUP), "position": [0.5, 0.0, 0.8]}
    plate = {**desc(PLATE_0), "id": "old2"}
    executor.store.create()
    executor.store.append_step(
        {"procedure": "run_skill", "args": {"skill": "serve"}, "bound": {"carried": blue, "landmark": plate}}
    )
    ran: list[tuple[str, dict[str, Any]]] = []
    replaying(executor, monkeypatch, ran)
    monkeypatch.setattr(executor.checks, "problem", lambda *args: None)
    command(executor, "execute", {})
    assert [(p, a.get("object")) for p, a in ran] == [("record", None), ("pick_up", "obj1"), ("place_rel", "obj2")]
    assert bus.said()[-1] == ("narration", "Completed action 2.")


def test_a_skill_that_runs_the_action_being_taught_is_run_but_not_recorded_in_it(
    robot: tuple[Executor, RecordingBus], monkeypatch: pytest.MonkeyPatch
) -> None:
    executor, bus = robot
    taught(executor, "serve")
    executor.store.create()  # action 2, being taught
    wrapper = executor.store.create()
    executor.store.append_step({"procedure": "run_skill", "args": {"skill": 2}, "bound": {}})
    executor.store.rename(wrapper, "wrap")
    executor.store.switch(2)
    monkeypatch.setattr(executor.replay, "replay", lambda *args, **kwargs: True)
    command(executor, "run_skill", {"skill": "wrap"})
    assert executor.store.step_counts() == [2, 0, 1]
    assert bus.said() == [
        ("info", "I didn't add it to action 2 as a step: \u201cwrap\u201d runs action 2 itself."),
    ]


def test_a_last_step_whose_effect_does_not_hold_is_reported_instead_of_completed(
    robot: tuple[Executor, RecordingBus], monkeypatch: pytest.MonkeyPatch
) -> None:
    executor, bus = robot
    taught(executor, None)
    ran: list[tuple[str, dict[str, Any]]] = []
    replaying(executor, monkeypatch, ran)
    held = RED  # the hand holds the red cup before the placement ...
    executor.procedures.set_held("right", Held("obj0", Box.of(held), np.zeros(7), seen_as=held))
    executor.replay.replay_step(
        "action 1", executor.store.get(1)["steps"], 2, executor.replay.ground(SERVE, 2, {}), (1,)
    )
    snap = executor.scene.snapshot()  # ... and sees it standing where it stood, off the plate
    assert ran == [("place_rel", {"arm": "right", "relation": "on_top_of", "object": "obj2"})]
    kind, text = bus.said()[-1]
    assert kind == "error" and text.startswith(f"{refer(snap.objects, 'obj0')[:1].upper()}")
    assert f"is not on top of {refer(snap.objects, 'obj2')}" in text
    assert text.endswith("So action 1 did not end as it was taught.")
    assert not any("Completed" in t for _, t in bus.said())


def test_a_role_not_said_whose_taught_object_is_gone_asks_for_one(robot: tuple[Executor, RecordingBus]) -> None:
    executor, bus = robot
    taught(executor, "serve")
    executor.scene.update_objects([RED, BLUE], TABLE)  # no plate on this table
    command(executor, "run_skill", {"skill": "serve", "objects": {"carried": "obj1"}})
    kind, text = bus.said()[-1]
    assert kind == "error" and text.startswith("There is no white plate on the table any more")
    assert text.endswith("Tell me which object to use in its place.") and bus.requests == []


def test_an_object_hidden_under_the_hand_that_let_go_is_looked_at_again_with_that_hand_aside(
    robot: tuple[Executor, RecordingBus], monkeypatch: pytest.MonkeyPatch
) -> None:
    executor, bus = robot
    held = PerceivedObject(id="obj0", color="red", type="cup", position=(0.6, 0.25, 0.87), size=CUP, visible=False)
    on_plate = PerceivedObject(id="obj0", color="red", type="cup", position=(0.6, 0.25, 0.815), size=CUP)
    executor.scene.update_objects([held, BLUE, PLATE_0], TABLE)  # stale, up where the hand let go of it
    aside: list[str] = []

    def move_aside(arm: str, destination: str = "side") -> None:
        aside.append(arm)
        executor.scene.update_objects([on_plate, BLUE, PLATE_0], TABLE)  # seen once the hand is out of the way

    monkeypatch.setattr(executor.perception, "record", lambda: list(executor.scene.snapshot().objects.values()))
    monkeypatch.setattr(executor.procedures, "move_abs_dest", move_aside)
    args = {"arm": "right", "relation": "on_top_of", "object": "obj2"}
    assert executor.checks.problem("place_rel", args, held, executor.scene.snapshot()) is None
    assert aside == ["right"]
