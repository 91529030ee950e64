"""What the executor's parts share: the situated status they write, and the way out they speak through.

The worker, the step runner, the replays and the reach loop each change a
part of what ``executor/state`` publishes, from different threads; the node
reads all of it to publish. Keeping those fields in one small object under
one lock, with who writes each field written beside it, makes the sharing
visible instead of hiding it in one class every part reaches into.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field
from typing import Any, Protocol

from services.executor.scene import ARMS
from shared.messages import SayKind


@dataclass
class Status:
    """The executor's situated status; ``lock`` guards the fields the reach loop and the node read."""

    lock: threading.Lock = field(default_factory=threading.Lock)
    busy: str | None = None  # the procedure the worker runs (worker)
    executing: bool = False  # an action is being replayed (replay; cleared by the worker)
    progress: dict[str, int] | None = None  # the replayed step, of how many (replay; cleared by the worker)
    last_arm: str | None = None  # the hand last told to do something (step runner)
    last_object: str | None = None  # what "it" refers to (step runner)
    reach: dict[str, Any] = field(default_factory=dict)  # object -> arm -> key -> reachable (reach loop)
    can_move: dict[str, dict[str, bool]] = field(default_factory=lambda: {arm: {} for arm in ARMS})  # (reach loop)
    # set by whatever may change what is reachable (objects, grippers, a fresh look, a command's end)
    reach_stale: threading.Event = field(default_factory=threading.Event)

    def command_waiting(self) -> bool:
        """Whether a command has been taken up (the reach map gives way to it)."""
        with self.lock:
            return self.busy is not None


class Outlet(Protocol):
    """How a part speaks and shows what changed: the node's ``dialog/say`` and ``executor/state``."""

    def say(self, text: str, kind: SayKind = "narration") -> None: ...

    def publish_state(self) -> None: ...
