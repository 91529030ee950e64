"""Programmed actions on disk: one JSON file, replaced atomically.

Why one file written by temp-file + fsync + rename: a process killed in the
middle of a save leaves either the old file or the new one, never a torn
mix, and the directory entry is synced too so the rename survives a power
cut. The service and the ``hfpbd executor actions`` tool may both edit the
file; every read checks the file's identity (mtime, size) and reloads when
someone else changed it, so neither works on a stale copy.
"""

from __future__ import annotations

import fcntl
import json
import os
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

FILE_NAME = "actions.json"
LOCK_NAME = "executor.lock"
DEFAULT_NAMESPACE = "default"
FORMAT_VERSION = 1
ENV_DATA_DIR = "HFPBD_DATA_DIR"


class StoreError(ValueError):
    """A request on the store that cannot be honoured (bad number, unreadable file)."""


def default_data_dir() -> Path:
    """``$HFPBD_DATA_DIR``, else ``$XDG_DATA_HOME/hfpbd``, else ``~/.local/share/hfpbd``."""
    if env := os.environ.get(ENV_DATA_DIR):
        return Path(env).expanduser()
    base = os.environ.get("XDG_DATA_HOME") or Path.home() / ".local" / "share"
    return Path(base) / "hfpbd"


def namespace_dir(data_dir: Path | str | None, namespace: str) -> Path:
    """``<data dir>/<namespace>``: each robot's actions apart from the others'.

    The default namespace takes over the store earlier versions kept at the
    top of the data directory (moved, once, so there is still one file).
    """
    base = Path(data_dir or default_data_dir())
    directory = base / namespace
    legacy = base / FILE_NAME
    if namespace == DEFAULT_NAMESPACE and legacy.is_file() and not (directory / FILE_NAME).exists():
        directory.mkdir(parents=True, exist_ok=True)
        os.replace(legacy, directory / FILE_NAME)
    return directory


def hold_store(directory: Path) -> IO[str]:
    """Lock ``directory``'s store for this executor for as long as the returned file stays open.

    Two executors never write one file: the second is refused, naming the
    holder's process id. The lock is the kernel's (``flock``), so it goes
    with the process however that ends.
    """
    directory.mkdir(parents=True, exist_ok=True)
    handle = open(directory / LOCK_NAME, "a+", encoding="utf-8")  # noqa: SIM115 — held open on purpose
    try:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        handle.seek(0)
        holder = handle.read().strip() or "another process"
        handle.close()
        raise StoreError(f"another executor (process {holder}) is using the actions in {directory}") from None
    handle.truncate(0)
    handle.write(str(os.getpid()))
    handle.flush()
    return handle


def atomic_write_text(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` so that readers see the old or the new content, never a part."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write(text)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    dir_fd = os.open(path.parent, os.O_RDONLY)
    try:
        os.fsync(dir_fd)
    finally:
        os.close(dir_fd)


class ActionStore:
    """The list of actions (1-based numbers) and which one is current.

    An action is ``{"name": str | None, "created": float, "steps": [step, ...]}``;
    a step is whatever the executor recorded (procedure, args, words, landmark
    descriptors, relative poses) and must be JSON-serialisable.
    """

    def __init__(self, data_dir: Path | str | None = None) -> None:
        self.path = Path(data_dir or default_data_dir()) / FILE_NAME
        self._lock = threading.RLock()
        self._actions: list[dict[str, Any]] = []
        self._current = 0
        self._seen: tuple[int, int] | None = None
        self._reload(force=True)

    # -- file ---------------------------------------------------------------
    def _identity(self) -> tuple[int, int] | None:
        try:
            st = self.path.stat()
        except FileNotFoundError:
            return None
        return (st.st_mtime_ns, st.st_size)

    def _reload(self, force: bool = False) -> None:
        identity = self._identity()
        if not force and identity == self._seen:
            return
        self._seen = identity
        if identity is None:
            self._actions, self._current = [], 0
            return
        try:
            data = json.loads(self.path.read_text(encoding="utf-8"))
        except (OSError, json.JSONDecodeError) as exc:
            raise StoreError(f"cannot read the actions file {self.path}: {exc}") from exc
        if not isinstance(data, dict) or not isinstance(data.get("actions"), list):
            raise StoreError(f"the actions file {self.path} is not an actions file")
        self._actions = [a for a in data["actions"] if isinstance(a, dict) and isinstance(a.get("steps"), list)]
        current = data.get("current", 0)
        self._current = current if isinstance(current, int) and 0 <= current <= len(self._actions) else 0
        if self._current == 0 and self._actions:
            self._current = 1

    def _save(self) -> None:
        data = {"version": FORMAT_VERSION, "current": self._current, "actions": self._actions}
        atomic_write_text(self.path, json.dumps(data, indent=1, sort_keys=True))
        self._seen = self._identity()

    # -- queries ------------------------------------------------------------
    @property
    def current(self) -> int:
        """The current action number (1-based), 0 when there is none."""
        with self._lock:
            self._reload()
            return self._current

    def count(self) -> int:
        with self._lock:
            self._reload()
            return len(self._actions)

    def step_counts(self) -> list[int]:
        with self._lock:
            self._reload()
            return [len(a["steps"]) for a in self._actions]

    def get(self, number: int) -> dict[str, Any]:
        with self._lock:
            self._reload()
            return json.loads(json.dumps(self._actions[self._index(number)]))

    def summaries(self) -> list[dict[str, Any]]:
        """One line per action: number, name, step count, creation time, whether current."""
        with self._lock:
            self._reload()
            return [
                {
                    "number": i + 1,
                    "name": a.get("name"),
                    "steps": len(a["steps"]),
                    "created": a.get("created"),
                    "current": i + 1 == self._current,
                }
                for i, a in enumerate(self._actions)
            ]

    def _index(self, number: int) -> int:
        if not isinstance(number, int) or isinstance(number, bool) or not 1 <= number <= len(self._actions):
            if not self._actions:
                raise StoreError(f"there is no action {number}: no actions have been created yet")
            raise StoreError(f"there is no action {number}: the actions are numbered 1 to {len(self._actions)}")
        return number - 1

    # -- changes ------------------------------------------------------------
    def create(self, name: str | None = None) -> int:
        """Append an empty action, make it current, and return its number."""
        with self._lock:
            self._reload()
            self._actions.append({"name": name, "created": time.time(), "steps": []})
            self._current = len(self._actions)
            self._save()
            return self._current

    def switch(self, number: int) -> int:
        with self._lock:
            self._reload()
            self._index(number)
            self._current = number
            self._save()
            return number

    def append_step(self, step: dict[str, Any]) -> tuple[int, int]:
        """Append to the current action (creating action 1 if none exists); return (action, step number)."""
        with self._lock:
            self._reload()
            if self._current == 0:
                self._actions.append({"name": None, "created": time.time(), "steps": []})
                self._current = len(self._actions)
            steps = self._actions[self._current - 1]["steps"]
            steps.append(json.loads(json.dumps(step)))
            self._save()
            return self._current, len(steps)

    def remove_last_step(self) -> dict[str, Any]:
        """Remove and return the current action's last step (an undo); StoreError when there is none."""
        with self._lock:
            self._reload()
            if self._current == 0 or not self._actions[self._current - 1]["steps"]:
                raise StoreError("there is no step to remove")
            step = self._actions[self._current - 1]["steps"].pop()
            self._save()
            return step

    def rename(self, number: int, name: str) -> None:
        if not name.strip():
            raise StoreError("an action's name cannot be empty")
        with self._lock:
            self._reload()
            self._actions[self._index(number)]["name"] = name.strip()
            self._save()

    def delete(self, number: int) -> None:
        """Remove an action; later ones move down by one, the current number follows its action."""
        with self._lock:
            self._reload()
            index = self._index(number)
            del self._actions[index]
            if self._current > number:
                self._current -= 1
            elif self._current == number:
                self._current = min(number, len(self._actions))
            self._save()

    def edit_steps(self, number: int, change: Callable[[list[dict[str, Any]]], None]) -> None:
        """Change one action's step list in place with ``change`` and save it, under the store's lock.

        ``change`` may raise ``StoreError`` to refuse; nothing is saved then.
        """
        with self._lock:
            self._reload()
            steps = json.loads(json.dumps(self._actions[self._index(number)]["steps"]))
            change(steps)
            self._actions[number - 1]["steps"] = steps
            self._save()
