"""Generate the corpus's seeded cases: ``python -m services.nlu.corpus.generate`` rewrites generated.jsonl.

Why generated as well as written: a few hundred hand-written lines cover the
ways people phrase things; generated scenes of 2–8 objects cover the ways
scenes differ (which colours and types repeat, where things stand, which hand
holds what). Each expected result follows from how the scene was built (the
object a phrase was made to name, the arm that was made to hold), never from
running the model. The same seed always gives the same file.
"""

from __future__ import annotations

import json
import random
from collections.abc import Iterator
from typing import Any

from services.nlu.corpus import HERE
from shared.contract import DISTANCE, other_arm

SEED = 19
SIZES = {"cup": (0.07, 0.07, 0.10), "box": (0.10, 0.10, 0.12), "plate": (0.18, 0.18, 0.02), "bowl": (0.13, 0.13, 0.06)}
COLORS = ("red", "green", "blue", "yellow", "orange", "purple", "white", "black")
XS = (0.45, 0.57, 0.69, 0.81)
YS = (-0.36, -0.24, -0.12, 0.0, 0.12, 0.24, 0.36)
RELATION_WORDS = {
    "above": ("above", "over"),
    "next_to": ("next to", "beside"),
    "left_of": ("to the left of",),
    "right_of": ("to the right of",),
    "in_front_of": ("in front of",),
    "behind": ("behind",),
    "on_top_of": ("on top of", "on"),
    "near": ("near",),
}
DIRECTION_WORDS = {
    "up": ("up", "upwards"),
    "down": ("down",),
    "left": ("to the left", "left"),
    "right": ("to the right", "right"),
    "forward": ("forward",),
    "backward": ("backward", "back"),
}
UNITS = {"centimetres": 0.01, "centimeters": 0.01, "cm": 0.01, "millimetres": 0.001, "mm": 0.001, "inches": 0.0254}
NUMBER_WORDS = {
    2: "two",
    3: "three",
    4: "four",
    5: "five",
    8: "eight",
    10: "ten",
    12: "twelve",
    15: "fifteen",
    20: "twenty",
    25: "twenty five",
}


def _object(i: int, color: str, kind: str, x: float, y: float) -> dict[str, Any]:
    size = SIZES[kind]
    return {"id": f"obj{i}", "color": color, "type": kind, "position": [x, y, 0.75 + size[2] / 2], "size": list(size)}


def _scene(rng: random.Random, count: int) -> list[dict[str, Any]]:
    cells = rng.sample([(x, y) for x in XS for y in YS], count)
    return [_object(i, rng.choice(COLORS), rng.choice(list(SIZES)), x, y) for i, (x, y) in enumerate(cells)]


def _world(objects: list[dict[str, Any]], **robot: Any) -> dict[str, Any]:
    base = {
        "grippers": {"right": "open", "left": "open"},
        "last_arm": "right",
        "last_object": None,
        "executing": False,
        "action": 1,
        "actions": [2, 3],
    }
    return {"objects": objects, "robot": {**base, **robot}}


def _unique_phrase(objects: list[dict[str, Any]], obj: dict[str, Any]) -> str | None:
    """ "the red cup" when no other object is a red cup (the type alone when it is the only one of its type)."""
    same_type = [o for o in objects if o["type"] == obj["type"]]
    if len(same_type) == 1:
        return f"the {obj['type']}"
    if sum(o["color"] == obj["color"] for o in same_type) == 1:
        return f"the {obj['color']} {obj['type']}"
    return None


class Builder:
    """Scenes and cases, accumulated."""

    def __init__(self, seed: int) -> None:
        self.rng = random.Random(seed)
        self.scenes: dict[str, Any] = {}
        self.cases: list[dict[str, Any]] = []

    def scene(self, world: dict[str, Any]) -> str:
        name = f"g{len(self.scenes)}"
        self.scenes[name] = world
        return name

    def add(self, category: str, scene: str, text: str, expect: dict[str, Any], **extra: Any) -> None:
        self.cases.append({"category": category, "scene": scene, "text": text, "expect": expect, **extra})


def command(procedure: str, then: list[dict[str, Any]] | None = None, **args: Any) -> dict[str, Any]:
    out: dict[str, Any] = {"kind": "command", "procedure": procedure, "args": args}
    if then:
        out["then"] = then
    return out


def step(procedure: str, **args: Any) -> dict[str, Any]:
    return {"procedure": procedure, "args": args}


def paper(b: Builder, rounds: int) -> None:
    """The paper's command space with explicit words, on random scenes."""
    for _ in range(rounds):
        objects = _scene(b.rng, b.rng.randint(2, 8))
        arm = b.rng.choice(("right", "left"))
        name = b.scene(_world(objects, last_arm=arm))
        named = [(o, p) for o in objects if (p := _unique_phrase(objects, o))]
        for obj, phrase in b.rng.sample(named, min(2, len(named))):
            verb = b.rng.choice(("pick up", "grab", "take"))
            b.add("paper", name, f"{verb} {phrase}", command("pick_up", arm=arm, object=obj["id"]))
            b.add(
                "paper", name, f"point at {phrase} with your {arm} hand", command("point_to", arm=arm, object=obj["id"])
            )
            b.add("paper", name, f"look at {phrase}", command("look_at", object=obj["id"]))
            relation = b.rng.choice(list(RELATION_WORDS))
            words = b.rng.choice(RELATION_WORDS[relation])
            b.add(
                "paper",
                name,
                f"move your {arm} hand {words} {phrase}",
                command("move_rel_dest", arm=arm, relation=relation, object=obj["id"]),
            )
            toward = b.rng.choice((("towards", "towards"), ("away from", "away_from")))
            b.add(
                "paper",
                name,
                f"move your {arm} hand {toward[0]} {phrase}",
                command("move_rel_dir", arm=arm, direction=toward[1], object=obj["id"]),
            )
        direction = b.rng.choice(list(DIRECTION_WORDS))
        b.add(
            "paper",
            name,
            f"move your {arm} hand {b.rng.choice(DIRECTION_WORDS[direction])}",
            command("move_abs_dir", arm=arm, direction=direction),
        )
        rotation = b.rng.choice((("clockwise", "cw"), ("counterclockwise", "ccw")))
        b.add("paper", name, f"rotate your {arm} hand {rotation[0]}", command("rotate", arm=arm, direction=rotation[1]))
        b.add("paper", name, f"close your {arm} hand", command("close", arm=arm))
        b.add("paper", name, f"move your {arm} arm to the side", command("move_abs_dest", arm=arm, destination="side"))


def hand_choice(b: Builder, rounds: int) -> None:
    """No hand used yet: the hand on the object's side."""
    for _ in range(rounds):
        objects = _scene(b.rng, b.rng.randint(2, 8))
        name = b.scene(_world(objects, last_arm=None))
        for obj in objects:
            phrase = _unique_phrase(objects, obj)
            y = obj["position"][1]
            if phrase is None or abs(y) < 0.1:
                continue
            arm = "right" if y < 0 else "left"
            verb = b.rng.choice(("pick up", "grab", "point to", "move above"))
            procedure = {"pick up": "pick_up", "grab": "pick_up", "point to": "point_to", "move above": "move_rel_dest"}
            args = {"arm": arm, "object": obj["id"]}
            if verb == "move above":
                args = {"arm": arm, "relation": "above", "object": obj["id"]}
            b.add("hand", name, f"{verb} {phrase}", command(procedure[verb], **args))


def held(b: Builder, rounds: int) -> None:
    """A hand holds an object: "it" is that object, that hand moves, and it is never the landmark."""
    for _ in range(rounds):
        objects = _scene(b.rng, b.rng.randint(3, 8))
        arm = b.rng.choice(("right", "left"))
        other = other_arm(arm)
        holder = objects[0]
        holder["held_by"] = arm
        name = b.scene(
            _world(objects, grippers={arm: "holding", other: "open"}, last_arm=arm, last_object=holder["id"])
        )
        b.add("held", name, "lift it", command("move_abs_dir", arm=arm, direction="up"))
        b.add("held", name, "raise it", command("move_abs_dir", arm=arm, direction="up"))
        direction = b.rng.choice(list(DIRECTION_WORDS))
        b.add(
            "held",
            name,
            f"move it {DIRECTION_WORDS[direction][0]}",
            command("move_abs_dir", arm=arm, direction=direction),
        )
        b.add("held", name, "put it down", command("place_abs", arm=arm, destination="table"))
        b.add("held", name, "pick it up", {"kind": "clarify", "params": [], "contains": "already holding"})
        b.add("held", name, "what are you holding", {"kind": "answer", "topic": "holding", "contains": arm})
        landmarks = [(o, p) for o in objects[1:] if (p := _unique_phrase(objects, o))]
        for obj, phrase in b.rng.sample(landmarks, min(2, len(landmarks))):
            b.add(
                "held",
                name,
                f"move it above {phrase}",
                command("move_rel_dest", arm=arm, relation="above", object=obj["id"]),
            )
            b.add(
                "held",
                name,
                f"put it on {phrase}",
                command("place_rel", arm=arm, relation="on_top_of", object=obj["id"]),
            )
            b.add(
                "held",
                name,
                f"place it next to {phrase}",
                command("place_rel", arm=arm, relation="next_to", object=obj["id"]),
            )
            theme = _unique_phrase(objects, holder)
            if theme is not None:
                b.add(
                    "held",
                    name,
                    f"put {theme} behind {phrase}",
                    command("place_rel", arm=arm, relation="behind", object=obj["id"]),
                )
            b.add(
                "held",
                name,
                f"move it towards {phrase}",
                command("move_rel_dir", arm=arm, direction="towards", object=obj["id"]),
            )


def _spread(
    b: Builder,
    kind: str,
    count: int,
    landmark: tuple[str, str],
    xy: list[tuple[float, float]],
    lm_xy: tuple[float, float],
) -> list[dict[str, Any]]:
    color = b.rng.choice(COLORS)
    objects = [_object(i, color, kind, x, y) for i, (x, y) in enumerate(xy[:count])]
    objects.append(_object(len(objects), landmark[0], landmark[1], *lm_xy))
    return objects


def _apart(a: dict[str, Any], b: dict[str, Any]) -> bool:
    return any(abs(a["position"][k] - b["position"][k]) > 0.1 for k in (0, 1))


def relational(b: Builder, rounds: int) -> None:
    """Two or three objects of one kind, told apart by where they stand against another one."""
    for _ in range(rounds):
        kind, lm_kind = b.rng.sample(["cup", "box", "bowl"], 2)
        lm = (b.rng.choice(COLORS), lm_kind)
        lx, ly = b.rng.choice((0.6, 0.7)), b.rng.choice((-0.1, 0.0, 0.1))
        near = (lx, ly + b.rng.choice((-0.14, 0.14)))
        far = (lx + b.rng.choice((-0.15, 0.15)), ly + (0.36 if near[1] < ly else -0.36))
        objects = _spread(b, kind, 2, lm, [near, far], (lx, ly))
        extra = [o for o in _scene(b.rng, 3) if o["type"] not in (kind, lm_kind) and all(_apart(o, p) for p in objects)]
        for o in extra[:1]:
            o["id"] = f"obj{len(objects)}"
            objects.append(o)
        name = b.scene(_world(objects, last_arm="right"))
        landmark = f"the {lm_kind}"
        verb = b.rng.choice(("pick up", "point to", "grab"))
        procedure = "point_to" if verb == "point to" else "pick_up"
        b.add(
            "relational", name, f"{verb} the {kind} next to {landmark}", command(procedure, arm="right", object="obj0")
        )
        b.add(
            "relational",
            name,
            f"{verb} the {kind} closest to {landmark}",
            command(procedure, arm="right", object="obj0"),
        )
        b.add(
            "relational",
            name,
            f"{verb} the {kind} farthest from {landmark}",
            command(procedure, arm="right", object="obj1"),
        )
        side = "left_of" if near[1] > ly else "right_of"
        words = "to the left of" if side == "left_of" else "on the right of"
        b.add("relational", name, f"look at the {kind} {words} {landmark}", command("look_at", object="obj0"))
        b.add(
            "relational",
            name,
            f"move above the {kind} next to {landmark}",
            command("move_rel_dest", arm="right", relation="above", object="obj0"),
        )
        order = sorted(range(2), key=lambda i: -objects[i]["position"][1])  # from the left
        b.add(
            "relational",
            name,
            f"pick up the first {kind} from the left",
            command("pick_up", arm="right", object=f"obj{order[0]}"),
        )
        b.add(
            "relational",
            name,
            f"pick up the second {kind} from the left",
            command("pick_up", arm="right", object=f"obj{order[1]}"),
        )
        b.add(
            "relational",
            name,
            f"point to the other {kind}",
            command("point_to", arm="right", object="obj1"),
            history={"last_arm": "right", "last_object": "obj0"},
        )
        # in front of / behind: a second scene with the two of a kind one before the other
        objects2 = _spread(b, kind, 2, lm, [(lx - 0.15, ly), (lx + 0.15, ly + 0.3)], (lx, ly))
        name2 = b.scene(_world(objects2, last_arm="left"))
        b.add(
            "relational",
            name2,
            f"point to the {kind} in front of {landmark}",
            command("point_to", arm="left", object="obj0"),
        )
        b.add(
            "relational", name2, f"pick up the {kind} behind {landmark}", command("pick_up", arm="left", object="obj1")
        )
        # between: one of a kind between two others, one outside them
        a, c = (0.6, -0.25), (0.6, 0.25)
        objects3 = [
            _object(0, "red", kind, 0.6, 0.0),
            _object(1, "red", kind, 0.8, 0.36),
            _object(2, lm[0], lm_kind, *a),
            _object(3, lm[0], lm_kind, *c),
        ]
        name3 = b.scene(_world(objects3, last_arm="right"))
        b.add(
            "relational",
            name3,
            f"point to the {kind} between the {lm_kind}s",
            command("point_to", arm="right", object="obj0"),
        )


def compound(b: Builder, rounds: int) -> None:
    """Several steps in one utterance, and a place with an empty hand that names what to place."""
    for _ in range(rounds):
        objects = _scene(b.rng, b.rng.randint(2, 8))
        arm = b.rng.choice(("right", "left"))
        name = b.scene(_world(objects, last_arm=arm))
        named = [(o, p) for o in objects if (p := _unique_phrase(objects, o))]
        if len(named) < 2:
            continue
        (first, p1), (second, p2) = b.rng.sample(named, 2)
        place = step("place_rel", arm=arm, relation="on_top_of", object=second["id"])
        joiner = b.rng.choice((" and ", " and then ", ", then ", " then "))
        b.add(
            "compound",
            name,
            f"pick up {p1}{joiner}put it on {p2}",
            command("pick_up", [place], arm=arm, object=first["id"]),
        )
        b.add("compound", name, f"put {p1} on {p2}", command("pick_up", [place], arm=arm, object=first["id"]))
        place_next = step("place_rel", arm=arm, relation="next_to", object=second["id"])
        b.add(
            "compound",
            name,
            f"grab {p1} and place it next to {p2}",
            command("pick_up", [place_next], arm=arm, object=first["id"]),
        )
        d1, d2 = b.rng.sample(["up", "down", "forward", "backward"], 2)
        b.add(
            "compound",
            name,
            f"move your {arm} hand {d1} then {d2}",
            command("move_abs_dir", [step("move_abs_dir", arm=arm, direction=d2)], arm=arm, direction=d1),
        )
        b.add(
            "compound",
            name,
            f"pick up {p1} and lift it",
            command("pick_up", [step("move_abs_dir", arm=arm, direction="up")], arm=arm, object=first["id"]),
        )
        b.add(
            "compound",
            name,
            f"point at {p1}, then look at {p2}",
            command("point_to", [step("look_at", object=second["id"])], arm=arm, object=first["id"]),
        )


def distances(b: Builder, rounds: int) -> None:
    """Distances in digits and words, units, "a little" and "a lot", and out of range."""
    name = b.scene(_world(_scene(b.rng, 4), last_arm="right"))
    for _ in range(rounds):
        arm = b.rng.choice(("right", "left"))
        direction = b.rng.choice(list(DIRECTION_WORDS))
        words = DIRECTION_WORDS[direction][0]
        unit = b.rng.choice(list(UNITS))
        limit = int(round(DISTANCE.max_m / UNITS[unit]))
        low = max(1, int(round(DISTANCE.min_m / UNITS[unit])) + 1)
        number = b.rng.randint(low, min(limit, 30 if unit != "mm" and unit != "millimetres" else 300))
        said = NUMBER_WORDS.get(number, str(number)) if b.rng.random() < 0.3 else str(number)
        metres = round(number * UNITS[unit], 4)
        if not DISTANCE.min_m <= metres <= DISTANCE.max_m:
            continue
        b.add(
            "distance",
            name,
            f"move your {arm} hand {words} {said} {unit}",
            command("move_abs_dir", arm=arm, direction=direction, distance=metres),
        )
    for words, metres in (
        ("a little", DISTANCE.a_little_m),
        ("a bit", DISTANCE.a_little_m),
        ("slightly", DISTANCE.a_little_m),
        ("a lot", DISTANCE.a_lot_m),
    ):
        for direction in DIRECTION_WORDS:
            b.add(
                "distance",
                name,
                f"move {DIRECTION_WORDS[direction][0]} {words}",
                command("move_abs_dir", arm="right", direction=direction, distance=metres),
            )
    for direction in DIRECTION_WORDS:
        b.add(
            "bad_input",
            name,
            f"move {DIRECTION_WORDS[direction][0]} 50 centimetres",
            {"kind": "clarify", "params": ["distance"], "contains": "30 cm"},
        )
        b.add(
            "bad_input",
            name,
            f"move {DIRECTION_WORDS[direction][0]} some centimetres",
            {"kind": "clarify", "params": ["distance"], "contains": "number"},
        )
        b.add(
            "bad_input",
            name,
            f"move your left hand {DIRECTION_WORDS[direction][0]} 2 metres",
            {"kind": "clarify", "params": ["distance"]},
        )


def typos(b: Builder, rounds: int) -> None:
    """The paper's commands with one slip of the fingers (two letters swapped) in a longer word."""
    from services.nlu.tokens import canonical, guessed

    for _ in range(rounds):
        objects = _scene(b.rng, b.rng.randint(2, 6))
        name = b.scene(_world(objects, last_arm="right"))
        named = [(o, p) for o in objects if (p := _unique_phrase(objects, o))]
        if not named:
            continue
        obj, phrase = b.rng.choice(named)
        text, expect = b.rng.choice(
            (
                (f"pick up {phrase}", command("pick_up", arm="right", object=obj["id"])),
                (f"point to {phrase}", command("point_to", arm="right", object=obj["id"])),
                (
                    f"move your right hand above {phrase}",
                    command("move_rel_dest", arm="right", relation="above", object=obj["id"]),
                ),
                (f"look at {phrase}", command("look_at", object=obj["id"])),
            )
        )
        words = text.split()
        long = [i for i, w in enumerate(words) if len(w) >= 5]
        if not long:
            continue
        i = b.rng.choice(long)
        word = words[i]
        j = b.rng.randint(1, len(word) - 3)
        typo = word[:j] + word[j + 1] + word[j] + word[j + 2 :]
        if typo == word or canonical(typo) != word:
            continue  # the swap made another word: not a typo the reader could know
        words[i] = typo
        if guessed(typo, word):  # a slip that made a real word ("geren"): offered for a yes, never run
            expect = {"kind": "clarify", "contains": f"I read '{typo}' as '{word}'. Did you mean"}
        b.add("typos", name, " ".join(words), expect)


def conversation(b: Builder) -> None:
    """Both hands, undo and repeat, questions, and bad input, on a few random scenes."""
    for _ in range(12):
        objects = _scene(b.rng, b.rng.randint(2, 8))
        name = b.scene(_world(objects, grippers={"right": "closed", "left": "closed"}, last_arm="right"))
        for text, expect in (
            ("open both hands", command("open", arm="both")),
            ("open both grippers", command("open", arm="both")),
            ("move both hands up", command("move_abs_dir", arm="both", direction="up")),
            ("move both arms to the side", command("move_abs_dest", arm="both", destination="side")),
            ("undo", command("undo")),
            ("undo that", command("undo")),
            ("take that back", command("undo")),
            ("again", command("repeat")),
            ("do it again", command("repeat")),
            ("repeat that", command("repeat")),
            ("what do you see", {"kind": "answer", "topic": "scene"}),
            ("what is on the table?", {"kind": "answer", "topic": "scene"}),
            ("what are you holding", {"kind": "answer", "topic": "holding", "contains": "empty"}),
            ("what is in action 2", {"kind": "answer", "topic": "actions", "contains": "3 steps"}),
            ("how many actions are there", {"kind": "answer", "topic": "actions"}),
            ("what can I say", {"kind": "answer", "topic": "help"}),
            ("help", {"kind": "answer", "topic": "help"}),
            ("", {"kind": "clarify", "params": []}),
            ("xyzzy plugh", {"kind": "clarify", "params": [], "contains": "xyzzy"}),
        ):
            b.add(
                "questions"
                if expect["kind"] == "answer"
                else "bad_input"
                if expect["kind"] == "clarify"
                else "conversation",
                name,
                text,
                expect,
            )
        named = [(o, p) for o in objects if (p := _unique_phrase(objects, o))]
        for obj, phrase in named[:2]:
            b.add("questions", name, f"where is {phrase}", {"kind": "answer", "topic": "object", "contains": "cm"})
            b.add(
                "bad_input",
                name,
                f"pick up {phrase} with both hands",
                {"kind": "clarify", "params": ["arm"], "contains": "one hand"},
            )
            b.add(
                "bad_input",
                name,
                f"point to {phrase} with your right and left hand",
                {"kind": "clarify", "params": ["arm"]},
            )
            b.add("questions", name, f"can you pick up {phrase}?", command("pick_up", arm="right", object=obj["id"]))


def build(seed: int = SEED) -> Builder:
    b = Builder(seed)
    paper(b, 40)
    hand_choice(b, 30)
    held(b, 30)
    relational(b, 30)
    compound(b, 40)
    distances(b, 120)
    typos(b, 200)
    conversation(b)
    return b


def cases() -> Iterator[dict[str, Any]]:
    yield from build().cases


def main() -> None:
    b = build()
    written = json.loads((HERE / "scenes.json").read_text()) if (HERE / "scenes.json").exists() else {}
    scenes = {k: v for k, v in written.items() if not k.startswith("g")} | b.scenes
    (HERE / "scenes.json").write_text(json.dumps(scenes, indent=None, separators=(",", ":")) + "\n")
    with open(HERE / "generated.jsonl", "w") as out:
        for case in b.cases:
            out.write(json.dumps(case) + "\n")
    print(f"{len(b.cases)} generated cases over {len(b.scenes)} scenes")


if __name__ == "__main__":
    main()
