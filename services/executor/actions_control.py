"""Managing programmed actions from the operator's screen: ``executor/control/actions``.

The command line's operations (``list``, ``show``, ``rename``, ``delete`` in
``actions_cli``) are extended here with what a person editing a program on
screen needs: every step in the user's words in the list, deleting or moving
one step, and running an action from a chosen step. Kept apart from the
executor's command handling so that both can change independently; the
executor only supplies the function that starts a run.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from services.executor.actions_cli import apply_action_op
from services.executor.grounding import describe_kind
from services.executor.store import ActionStore, StoreError
from shared.messages import (
    ACTIONS_REPLIES,
    ActionList,
    ActionStarted,
    Reply,
    StepDeleted,
    StepMoved,
    reply_from,
)

# starts a run of action ``number`` from step ``start`` (1-based); returns (accepted, why not)
Runner = Callable[[int, int], tuple[bool, str]]

OPERATIONS = "list, show, rename, delete, delete_step, move_step or execute"


def step_words(step: dict[str, Any]) -> str:
    """A step as the user said it; a step given without words (a key) is spelled from its procedure.

    One step of a compound ("part") is named by its own sentence: the
    utterance's words cover all of its steps.
    """
    said = None if step.get("part") else step.get("utterance")
    if said or step.get("text"):
        return str(said or step.get("text"))
    args = step.get("args", {})
    if step["procedure"] == "run_skill":  # its objects are ids of the day: named by how they looked
        skill = args.get("skill")
        seen = [
            f"the {describe_kind(d)}" for d in [*(step.get("bound") or {}).values(), *(step.get("each_seen") or [])]
        ]
        called = f"action {skill}" if isinstance(skill, int) else str(skill)
        return f"{called} with {' and '.join(seen)}" if seen else called
    landmark = step.get("landmark")
    parts = [step["procedure"].replace("_", " ")]
    parts += [str(v).replace("_", " ") for k, v in args.items() if k != "object"]
    if landmark:
        parts.append(f"the {describe_kind(landmark)}")
    return " ".join(parts)


def apply(store: ActionStore, request: dict[str, Any], run: Runner | None = None) -> Reply:
    """Answer one request; ``StoreError`` (a ``ValueError``) carries the reason for a refusal."""
    op = request.get("op")
    if op == "list":
        listed = apply_action_op(store, request)
        for item in listed["actions"]:
            item["words"] = [step_words(s) for s in store.get(item["number"])["steps"]]
        return reply_from(ActionList, listed)
    if op in ("show", "rename", "delete"):
        return reply_from(ACTIONS_REPLIES[op], apply_action_op(store, request))  # the command line's maps, typed
    if op not in ("delete_step", "move_step", "execute"):
        raise StoreError(f"unknown actions operation {op!r}; use {OPERATIONS}")
    number = _whole(request.get("number"), "number")
    count = len(store.get(number)["steps"])
    step = _whole(request.get("step", 1), "step")
    if not 1 <= step <= count:
        raise StoreError(_no_step(number, step, count))
    if op == "execute":
        if run is None:
            raise StoreError("actions can only be executed by the running executor")
        accepted, why = run(number, step)
        if not accepted:
            raise StoreError(why)
        return ActionStarted(ok=True, number=number, step=step, message=why)
    if op == "delete_step":

        def delete(steps: list[dict[str, Any]]) -> None:
            steps.pop(step - 1)

        store.edit_steps(number, delete)
        return StepDeleted(ok=True, number=number, steps=count - 1)
    to = _whole(request.get("to"), "to")
    if not 1 <= to <= count:
        raise StoreError(f"cannot move step {step} to {to}: action {number} has steps 1 to {count}")
    store.edit_steps(number, lambda steps: steps.insert(to - 1, steps.pop(step - 1)))
    return StepMoved(ok=True, number=number, step=step, to=to)


def _whole(value: Any, field: str) -> int:
    """A 1-based number from the request (digits in a string are accepted, as on the command line)."""
    if isinstance(value, str) and value.isdigit():
        return int(value)
    if isinstance(value, int) and not isinstance(value, bool):
        return value
    raise StoreError(f"the request needs a whole number for {field!r}, not {value!r}")


def _no_step(number: int, step: int, count: int) -> str:
    if count == 0:
        return f"there is no step {step}: action {number} has no steps yet"
    return f"there is no step {step} in action {number}: its steps are numbered 1 to {count}"
