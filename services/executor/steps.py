"""One step: checked, narrated, run and, when it is taught, recorded into the current action.

A command's steps and a replay's steps go through the same runner, so a
replayed step is refused, narrated and said to have failed exactly as it was
when it was taught; only a taught step is written to the store (with the
state before it, for undo, and its landmark as the user named it, for the
replay).
"""

from __future__ import annotations

from typing import Any

from services.executor import said, wording
from services.executor.commands import ADMIN, BOTH, RECORDED, Step
from services.executor.origins import Origins
from services.executor.procedures import Procedures, StepFailed
from services.executor.referring import refer
from services.executor.robot import Stopped
from services.executor.scene import ARMS, Scene, SceneSnapshot
from services.executor.status import Outlet, Status
from services.executor.store import ActionStore
from services.executor.undo import before_state
from shared.contract import PLACES


class StepRunner:
    """Runs one procedure at a time for the worker and the replays; writes ``status``'s last hand and object."""

    def __init__(
        self,
        scene: Scene,
        procedures: Procedures,
        origins: Origins,
        store: ActionStore,
        status: Status,
        out: Outlet,
    ) -> None:
        self.scene = scene
        self.procedures = procedures
        self.origins = origins
        self.store = store
        self.status = status
        self.out = out

    def run(
        self,
        procedure: str,
        args: dict[str, Any],
        context: dict[str, Any],
        *,
        keep: bool,
        preferred: list[float] | None = None,
        failure_note: str | None = None,
        coming: dict[str, str] | None = None,
    ) -> bool:
        """Narrate, run and (when ``keep``) record one procedure; False when it failed or was stopped.

        ``failure_note`` is added to the error sentence (which step of a
        compound this was); ``coming``: the placement a pick-up is followed by.
        """
        snap = self.scene.snapshot()
        if procedure not in ADMIN:
            if args.get("arm") != BOTH:
                self.status.last_arm = args.get("arm", self.status.last_arm)
            self.status.last_object = self._referent(procedure, args) or self.status.last_object

        def failed(text: str) -> bool:
            self.out.say(f"{text} {failure_note}" if failure_note else text, "error")
            return False

        extra: dict[str, Any] = {}
        back: str | None = None  # the object a place_back puts back
        try:
            self.procedures.precheck(procedure, args)
            if procedure == "place_back":
                back, extra = self.origin(args, snap)
        except StepFailed as exc:
            return failed(str(exc))
        if procedure == "place_back":  # the held object is the hand's: an id would not be found again on replay
            args = {"arm": args["arm"]}
        before = before_state(snap, self.procedures) if keep and procedure in RECORDED else None
        held_words = self.procedures.held_description(args["arm"], snap) if "arm" in args else None
        if procedure != "record":
            self.out.say(
                wording.narration(
                    procedure, args, context.get("phrases"), lambda oid: refer(snap.objects, oid), held=held_words
                )
            )
        kwargs = {**args, **extra}
        if preferred is not None and procedure == "move_rel_dest":
            kwargs["preferred"] = preferred
        if coming is not None:
            kwargs["coming"] = coming
        try:
            done = self.procedures.run(procedure, kwargs)
        except Stopped:
            self.out.say("Stopped.", "info")
            return False
        except StepFailed as exc:
            return failed(str(exc))
        if done.message:
            self.out.say(done.message, "info")
        if procedure == "pick_up":
            self.origins.picked(snap.objects[args["object"]], self.scene.snapshot().objects)
        elif back is not None:
            self.origins.returned(back)
        if before is not None:
            step = {
                "procedure": procedure,
                "args": args,
                "phrases": context.get("phrases", {}),
                "text": context.get("text", ""),
                "utterance": context.get("utterance", ""),
                "landmark": _remembered(done.landmark, context, snap),
                "relative_pose": done.relative_pose,
                "before": before,
            }
            if context.get("part"):
                step["part"] = context["part"]
            self.store.append_step(step)
            self.out.publish_state()
        return True

    def _referent(self, procedure: str, args: dict[str, Any]) -> str | None:
        """What "it" refers to once this step is done: after a placement the object put down, not the place.

        The NLU keeps the same rule (``History.after``), so the two accounts
        of history agree.
        """
        if procedure in PLACES and args.get("arm") in ARMS:
            held = self.procedures.held()[args["arm"]]
            if held is not None:
                return held.object_id
        return args.get("object")

    def origin(self, args: dict[str, Any], snap: SceneSnapshot) -> tuple[str, dict[str, Any]]:
        """For ``place_back``: the held object (it must be the one named, if one is) and where it stood."""
        arm = args["arm"]
        held = self.procedures.held()[arm]
        if held is None:  # the precheck refuses an empty hand first
            raise StepFailed(wording.not_holding(arm, "put back"))
        named = args.get("object")
        if named is not None and named != held.object_id and snap.objects[named].held_by != arm:
            raise StepFailed(
                wording.sentence(
                    f"My {arm} hand is holding {refer(snap.objects, held.object_id, held.seen_as)}, "
                    f"not {refer(snap.objects, named)}"
                )
            )
        spot = self.origins.spot(held.object_id)
        if spot is None:
            words = refer(snap.objects, held.object_id, held.seen_as)
            raise StepFailed(
                wording.sentence(
                    f"I haven't moved {words} from anywhere else since I started, so I don't know where it was "
                    "before; tell me where to put it"
                )
            )
        return held.object_id, {"center": spot.tolist()}


def _remembered(landmark: dict[str, Any] | None, context: dict[str, Any], snap: SceneSnapshot) -> dict[str, Any] | None:
    """A step's landmark as recorded: its look, and the words that named it then (see :mod:`said`)."""
    if landmark is None:
        return None
    unique_as = refer(snap.objects, landmark["id"]) if landmark["id"] in snap.objects else None
    return {**landmark, **said.remembered_words(context.get("phrases") or {}, unique_as)}


def context(step: Step, utterance: str) -> dict[str, Any]:
    """What a step keeps of the user's words: the phrases and sentence of that step, the whole utterance."""
    return {"phrases": step.phrases, "text": step.text, "utterance": utterance}


def coming(procedure: str, args: dict[str, Any], after: str, after_args: dict[str, Any]) -> dict[str, str] | None:
    """What a pick-up is to be followed by, when the next step places the object by the same hand beside or
    on another (``Procedures.pick_up`` then grasps it so that it can be set down there)."""
    if procedure != "pick_up" or after != "place_rel" or after_args.get("arm") != args.get("arm"):
        return None
    return {"relation": str(after_args["relation"]), "object": str(after_args["object"])}
