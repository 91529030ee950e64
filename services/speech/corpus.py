"""A spoken-command corpus over fixed scenes: sentences, the commands they mean, and voices.

The paper's commands come first, then the conversation beyond it (DESIGN.md):
distances, both hands, questions, undo, repeat and steps joined by "and then",
each under its category so the benchmark can say how each form is heard.
Every procedure appears in every scene; each sentence names its objects by
the scene's own referring expressions, and the robot state is set so that
the intended command is the sensible one (a hand holds something before a
place, execution runs before a stop). Voices and speeds rotate so the
recogniser is not tuned to one synthetic speaker.

The held-out set is the same sentences in other voices and speeds, twice
over; weights and thresholds are chosen on it, so that the benchmark stays a
check rather than a training set.
"""

from __future__ import annotations

import copy
import itertools
from dataclasses import dataclass
from typing import Any

VOICES = ("en-us", "en-gb", "en-us+f3", "en-gb-x-rp", "en-us+m3", "en-gb-scotland")
SPEEDS = (130, 150, 170, 185)
HELD_OUT_VOICES = ("en-us+f2", "en-gb-x-gbclan", "en-us+m5", "en-029", "en-gb+f4", "en-us-nyc")
HELD_OUT_SPEEDS = (140, 160, 175, 195)
HELD_OUT_ROUNDS = 2

_CUP = [0.07, 0.07, 0.10]
_BOX = [0.08, 0.08, 0.08]
_PLATE = [0.20, 0.20, 0.02]

# scene name -> (objects, {placeholder: (words, object id)})
SCENES: dict[str, tuple[list[dict[str, Any]], dict[str, tuple[str, str]]]] = {
    "cups": (
        [
            {"id": "obj0", "color": "red", "type": "cup", "position": [0.55, -0.15, 0.77], "size": _CUP},
            {"id": "obj1", "color": "blue", "type": "cup", "position": [0.60, 0.15, 0.77], "size": _CUP},
            {"id": "obj2", "color": "green", "type": "box", "position": [0.50, 0.00, 0.76], "size": _BOX},
            {"id": "obj3", "color": "white", "type": "plate", "position": [0.70, 0.00, 0.73], "size": _PLATE},
        ],
        {"a": ("the red cup", "obj0"), "b": ("the blue cup", "obj1"), "c": ("the green box", "obj2")},
    ),
    "colours": (
        [
            {
                "id": "obj0",
                "color": "yellow",
                "type": "bowl",
                "position": [0.55, 0.10, 0.76],
                "size": [0.14, 0.14, 0.07],
            },
            {"id": "obj1", "color": "red", "type": "box", "position": [0.65, -0.10, 0.76], "size": _BOX},
            {"id": "obj2", "color": "purple", "type": "cup", "position": [0.50, -0.20, 0.77], "size": _CUP},
            {"id": "obj3", "color": "orange", "type": "plate", "position": [0.70, 0.20, 0.73], "size": _PLATE},
        ],
        {"a": ("the yellow bowl", "obj0"), "b": ("the red box", "obj1"), "c": ("the purple cup", "obj2")},
    ),
    "labels": (
        [
            {"id": "obj0", "color": "red", "type": "cup", "position": [0.55, 0.25, 0.77], "size": _CUP},
            {"id": "obj1", "color": "red", "type": "cup", "position": [0.55, -0.05, 0.77], "size": _CUP},
            {"id": "obj2", "color": "blue", "type": "box", "position": [0.65, 0.05, 0.78], "size": [0.14, 0.14, 0.12]},
            {"id": "obj3", "color": "blue", "type": "box", "position": [0.50, -0.25, 0.75], "size": [0.05, 0.05, 0.05]},
        ],
        {"a": ("the leftmost cup", "obj0"), "b": ("the biggest box", "obj2"), "c": ("the smallest box", "obj3")},
    ),
}


def _move(arm: str, direction: str, distance: float | None = None) -> dict[str, Any]:
    args: dict[str, Any] = {"arm": arm, "direction": direction}
    if distance is not None:
        args["distance"] = distance
    return {"procedure": "move_abs_dir", "args": args}


# robot state name -> the world's robot fields
STATES: dict[str, dict[str, Any]] = {
    "right": {"grippers": {"right": "open", "left": "open"}, "last_arm": "right"},
    "left": {"grippers": {"right": "open", "left": "open"}, "last_arm": "left"},
    "holding": {"grippers": {"right": "holding", "left": "open"}, "last_arm": "right", "last_object": "obj0"},
    "grippers": {"grippers": {"right": "closed", "left": "open"}, "last_arm": "right"},
    "first_action": {"grippers": {"right": "open", "left": "open"}, "action": 1, "actions": [3, 2, 4]},
    "second_action": {"grippers": {"right": "open", "left": "open"}, "action": 2, "actions": [3, 2, 4]},
    "executing": {"grippers": {"right": "open", "left": "open"}, "executing": True, "action": 1, "actions": [3]},
}

# (sentence with {a} {b} {c} object placeholders, robot state, procedure, args with "a"/"b"/"c" for objects)
TEMPLATES: list[tuple[str, str, str, dict[str, Any]]] = [
    ("move your right hand above {a}", "right", "move_rel_dest", {"arm": "right", "relation": "above", "object": "a"}),
    ("move your left arm next to {b}", "right", "move_rel_dest", {"arm": "left", "relation": "next_to", "object": "b"}),
    (
        "move your right hand behind {c}",
        "right",
        "move_rel_dest",
        {"arm": "right", "relation": "behind", "object": "c"},
    ),
    (
        "move your left hand in front of {a}",
        "left",
        "move_rel_dest",
        {"arm": "left", "relation": "in_front_of", "object": "a"},
    ),
    ("move your right arm to the side", "right", "move_abs_dest", {"arm": "right", "destination": "side"}),
    ("tuck your left arm", "right", "move_abs_dest", {"arm": "left", "destination": "side"}),
    ("move your right hand up", "right", "move_abs_dir", {"arm": "right", "direction": "up"}),
    ("move your left hand down", "left", "move_abs_dir", {"arm": "left", "direction": "down"}),
    ("raise your left arm", "right", "move_abs_dir", {"arm": "left", "direction": "up"}),
    ("move your right hand forward", "right", "move_abs_dir", {"arm": "right", "direction": "forward"}),
    ("move your left arm backward", "left", "move_abs_dir", {"arm": "left", "direction": "backward"}),
    (
        "move your right hand towards {b}",
        "right",
        "move_rel_dir",
        {"arm": "right", "direction": "towards", "object": "b"},
    ),
    (
        "move your left hand away from {a}",
        "left",
        "move_rel_dir",
        {"arm": "left", "direction": "away_from", "object": "a"},
    ),
    ("pick up {a} with your right hand", "right", "pick_up", {"arm": "right", "object": "a"}),
    ("pick up {b} with your left hand", "right", "pick_up", {"arm": "left", "object": "b"}),
    ("grab {c}", "right", "pick_up", {"arm": "right", "object": "c"}),
    ("pick {b} up", "left", "pick_up", {"arm": "left", "object": "b"}),
    ("place it on the table", "holding", "place_abs", {"arm": "right", "destination": "table"}),
    ("place it here", "holding", "place_abs", {"arm": "right", "destination": "here"}),
    ("place it on top of {b}", "holding", "place_rel", {"arm": "right", "relation": "on_top_of", "object": "b"}),
    (
        "place it next to {c} with your right hand",
        "holding",
        "place_rel",
        {"arm": "right", "relation": "next_to", "object": "c"},
    ),
    ("point to {a} with your left hand", "right", "point_to", {"arm": "left", "object": "a"}),
    ("point at {b}", "right", "point_to", {"arm": "right", "object": "b"}),
    ("look at {c}", "right", "look_at", {"object": "c"}),
    ("look at {a}", "left", "look_at", {"object": "a"}),
    ("rotate your right hand clockwise", "right", "rotate", {"arm": "right", "direction": "cw"}),
    ("turn your left hand counterclockwise", "left", "rotate", {"arm": "left", "direction": "ccw"}),
    ("open your right hand", "grippers", "open", {"arm": "right"}),
    ("close your left hand", "grippers", "close", {"arm": "left"}),
    ("record objects", "right", "record", {}),
    ("create a new action", "right", "create_action", {}),
    ("switch to the next action", "first_action", "switch_action", {"target": "next"}),
    ("switch to the previous action", "second_action", "switch_action", {"target": "previous"}),
    ("switch to action three", "first_action", "switch_action", {"target": 3}),
    ("execute", "first_action", "execute", {}),
    ("stop", "executing", "stop", {}),
    ("please stop", "executing", "stop", {}),
]

PAPER = "paper"
# (category, sentence, robot state, meaning): a command {"procedure", "args"[, "then"]} or a question {"answer"}
CONVERSATION: list[tuple[str, str, str, dict[str, Any]]] = [
    ("distance", "move your right hand up five centimetres", "right", _move("right", "up", 0.05)),
    ("distance", "move your left hand down ten centimetres", "left", _move("left", "down", 0.10)),
    ("distance", "move your right hand forward three centimetres", "right", _move("right", "forward", 0.03)),
    ("distance", "raise your left arm twenty centimetres", "right", _move("left", "up", 0.20)),
    ("both", "open both hands", "grippers", {"procedure": "open", "args": {"arm": "both"}}),
    ("both", "close both hands", "right", {"procedure": "close", "args": {"arm": "both"}}),
    ("both", "move both hands up", "right", _move("both", "up")),
    (
        "both",
        "move both arms to the side",
        "right",
        {"procedure": "move_abs_dest", "args": {"arm": "both", "destination": "side"}},
    ),
    ("question", "what are you holding", "holding", {"answer": "holding"}),
    ("question", "where is {a}", "right", {"answer": "object"}),
    ("question", "what do you see", "right", {"answer": "scene"}),
    ("undo", "undo", "right", {"procedure": "undo", "args": {}}),
    ("undo", "undo that", "left", {"procedure": "undo", "args": {}}),
    ("repeat", "again", "right", {"procedure": "repeat", "args": {}}),
    ("repeat", "do it again", "left", {"procedure": "repeat", "args": {}}),
    (
        "then",
        "pick up {a} and then place it on the table",
        "right",
        {
            "procedure": "pick_up",
            "args": {"arm": "right", "object": "a"},
            "then": [{"procedure": "place_abs", "args": {"arm": "right", "destination": "table"}}],
        },
    ),
    (
        "then",
        "move your left hand up and then open your left hand",
        "left",
        {**_move("left", "up"), "then": [{"procedure": "open", "args": {"arm": "left"}}]},
    ),
]


@dataclass(frozen=True)
class Item:
    """One corpus utterance: what is said, by which voice, and what it must mean."""

    scene: str
    text: str
    world: dict[str, Any]
    expected: dict[str, Any]
    voice: str
    speed: int
    category: str = PAPER


def _templates() -> list[tuple[str, str, str, dict[str, Any]]]:
    paper = [(PAPER, s, state, {"procedure": p, "args": args}) for s, state, p, args in TEMPLATES]
    return paper + CONVERSATION


def _resolved(meaning: dict[str, Any], refs: dict[str, tuple[str, str]]) -> dict[str, Any]:
    """The meaning with each object placeholder ("a") replaced by the scene's object id."""
    out = dict(meaning)
    if "args" in out:
        out["args"] = {k: refs[v][1] if k == "object" else v for k, v in out["args"].items()}
    if "then" in out:
        out["then"] = [_resolved(step, refs) for step in out["then"]]
    return out


def corpus(voices: tuple[str, ...] = VOICES, speeds: tuple[int, ...] = SPEEDS, rounds: int = 1) -> list[Item]:
    """Every template in every scene (162 utterances) ``rounds`` times, voices and speeds rotating."""
    items: list[Item] = []
    for _round, (scene, (objects, refs)) in itertools.product(range(rounds), SCENES.items()):
        for category, sentence, state, meaning in _templates():
            n = len(items)
            text = sentence.format(**{k: words for k, (words, _) in refs.items()})
            world = {"objects": copy.deepcopy(objects), "robot": copy.deepcopy(STATES[state])}
            if state == "holding":
                world["objects"][0]["held_by"] = "right"
            items.append(
                Item(
                    scene,
                    text,
                    world,
                    _resolved(meaning, refs),
                    voices[n % len(voices)],
                    speeds[(n // len(voices)) % len(speeds)],
                    category,
                )
            )
    return items


def held_out() -> list[Item]:
    """The sentences of :func:`corpus` in other voices and speeds (324 utterances), for choosing weights."""
    return corpus(HELD_OUT_VOICES, HELD_OUT_SPEEDS, HELD_OUT_ROUNDS)
