"""A dry run of a task script through the language model alone (no robot, no network).

Why: a script is only worth running on the robot if each utterance, in the
context the previous steps leave, means what the script intends. Here the
world state starts from the scene file and each expected command changes it
the way the robot would (a picked-up object is held and lifted, a placed one
lands by its landmark, the last arm and object are remembered); the NLU's own
:class:`Dialogue` carries the conversation exactly as the service does. A
compound changes the world step by step, "again" does the last command once
more and "undo" takes the last step's change back.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any

from hfpbd.tasks.scripts import Expected, Task, Utterance
from services.nlu.context import Dialogue
from services.nlu.infer import Clarify, Model
from services.nlu.world import parse_world
from services.sim.scene_file import load_scene

ADMIN = {"record", "create_action", "switch_action", "execute", "stop"}
LIFT = 0.12  # a picked-up object rises about this much
GAP = 0.05  # a placed object lands this far from its landmark's side


@dataclass(frozen=True)
class Rehearsed:
    """One utterance: what the model made of it, and whether that is what the script expects."""

    utterance: Utterance
    understood: dict[str, Any]  # the parse JSON (command or clarify)

    @property
    def ok(self) -> bool:
        return self.understood.get("kind") == "command" and _meaning(self.understood) == self.utterance.expect.as_dict()

    def explain(self) -> str:
        if self.understood.get("kind") != "command":
            return f"{self.utterance.text!r}: the robot asked {self.understood.get('question')!r}"
        return f"{self.utterance.text!r}: understood {_meaning(self.understood)}, expected {self.utterance.expect.as_dict()}"


def _meaning(understood: dict[str, Any]) -> dict[str, Any]:
    """A command result as a script's ``expect``: procedure, args and, for a compound, the further steps."""
    out: dict[str, Any] = {"procedure": understood.get("procedure"), "args": understood.get("args")}
    if understood.get("then"):
        out["then"] = [{"procedure": step["procedure"], "args": step["args"]} for step in understood["then"]]
    return out


def initial_world(scene_name: str) -> dict[str, Any]:
    """The world-state JSON perception and the executor would report for a freshly loaded scene."""
    scene = load_scene(scene_name)
    objects = [
        {
            "id": o.id,
            "color": o.color,
            "type": o.type,
            "position": list(o.position),
            "size": list(o.size),
            "held_by": None,
        }
        for o in scene.objects
    ]
    robot = {"grippers": {"right": "open", "left": "open"}, "last_arm": None, "last_object": None, "executing": False}
    return {"objects": objects, "robot": robot}


def rehearse(task: Task, style: str) -> list[Rehearsed]:
    """Parse every utterance of one script in order; the world follows the *expected* commands."""
    world = initial_world(task.scene)
    dialogue = Dialogue()
    results = []
    before: list[dict[str, Any]] = []  # the world before each step, for "undo"
    last: tuple[Expected, ...] = ()  # the last command's steps, for "again"
    for utterance in task.script(style):
        result = dialogue.understand(Model(parse_world(world)), utterance.text)
        results.append(Rehearsed(utterance, result.to_json()))
        if isinstance(result, Clarify):
            dialogue.pending = None  # the script does not answer questions; the next line starts afresh
        expect = utterance.expect
        if expect.procedure == "undo":
            world = before.pop() if before else world
        else:
            steps = last if expect.procedure == "repeat" else expect.commands
            if expect.procedure not in ADMIN | {"repeat"}:
                last = steps
            for step in steps:
                if step.procedure not in ADMIN:
                    before.append(world)
                world = after(world, step.procedure, step.args)
        dialogue.observe_robot()  # the executor's state report takes over the history
    return results


def after(world: dict[str, Any], procedure: str, args: dict[str, Any]) -> dict[str, Any]:
    """The world state once the robot has done ``procedure`` (only what the language model looks at)."""
    world = copy.deepcopy(world)
    robot, objects = world["robot"], {o["id"]: o for o in world["objects"]}
    arm, target = args.get("arm"), args.get("object")
    if procedure not in ADMIN:
        robot["last_arm"] = arm if arm in ("right", "left") else robot["last_arm"]
        robot["last_object"] = target or robot["last_object"]
    held = next((o for o in objects.values() if o["held_by"] == arm), None) if arm else None
    if procedure == "pick_up":
        objects[target]["held_by"] = arm
        objects[target]["position"][2] += LIFT
        robot["grippers"][arm] = "holding"
    elif procedure in ("place_rel", "place_abs", "open") and held is not None:
        if procedure == "place_rel":
            held["position"] = _placed(held, objects[target], args["relation"])
        else:
            held["position"][2] -= LIFT
        held["held_by"] = None
        robot["grippers"][arm] = "open"
    elif procedure == "open":
        robot["grippers"][arm] = "open"
    elif procedure == "close":
        robot["grippers"][arm] = "closed"
    return world


def _placed(held: dict[str, Any], landmark: dict[str, Any], relation: str) -> list[float]:
    """Where a placed object ends up relative to its landmark (centre of its box)."""
    (x, y, z), (lx, ly, lz) = landmark["position"], landmark["size"]
    hx, hy, hz = held["size"]
    table_z = z - lz / 2
    if relation in ("on_top_of", "above"):
        return [x, y, z + lz / 2 + hz / 2]
    offsets = {
        "left_of": (0.0, ly / 2 + GAP + hy / 2),
        "next_to": (0.0, -(ly / 2 + GAP + hy / 2)),
        "right_of": (0.0, -(ly / 2 + GAP + hy / 2)),
        "near": (0.0, -(ly / 2 + GAP + hy / 2)),
        "in_front_of": (-(lx / 2 + GAP + hx / 2), 0.0),
        "behind": (lx / 2 + GAP + hx / 2, 0.0),
    }
    dx, dy = offsets[relation]
    return [x + dx, y + dy, table_z + hz / 2]
