"""The command in progress, on disk, so an executor killed in the middle of one can say so when it is back.

Why a file: a SIGKILL leaves no chance to tell anyone; the supervisor
restarts the executor, which would otherwise come back as if nothing had
happened while the person waits for a pick-up that will never finish. The
marker is written (atomically, like the actions) when the worker takes a
command up and removed when it ends however it ends; one still there at
start is a command that was cut short. It sits in the namespace's data
directory, which only one executor holds at a time.
"""

from __future__ import annotations

import json
import logging
from pathlib import Path

from services.executor.store import atomic_write_text

log = logging.getLogger("hfpbd.executor")

MARKER_NAME = "in_progress.json"


class InProgress:
    """The marker file of one data directory."""

    def __init__(self, directory: Path) -> None:
        self.path = Path(directory) / MARKER_NAME

    def begin(self, doing: str) -> None:
        """Note that the command described by ``doing`` ("picking up the red cup") has started."""
        atomic_write_text(self.path, json.dumps({"v": 1, "doing": doing}))

    def end(self) -> None:
        self.path.unlink(missing_ok=True)

    def take(self) -> str | None:
        """What was being done when the previous executor died (None if it ended cleanly); clears the marker."""
        try:
            text = self.path.read_text(encoding="utf-8")
        except FileNotFoundError:
            return None
        except OSError as exc:
            log.warning("cannot read %s: %s", self.path, exc)
            return None
        self.end()
        try:
            doing = json.loads(text).get("doing")
        except (json.JSONDecodeError, AttributeError):
            doing = None
        return doing if isinstance(doing, str) and doing else "a command"


def interrupted_sentence(doing: str, action: int, steps: int) -> str:
    """What the restarted executor says: what was cut short, and that the taught steps are all there."""
    kept = f" Action {action} still has {steps} step{'s' if steps != 1 else ''}." if action else ""
    return f"I was interrupted while {doing}: I had to restart, so it was not finished.{kept} Tell me what to do next."
