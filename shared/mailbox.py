"""A small thread-safe hand-off from Zenoh's callback threads to a worker.

Zenoh callbacks must never block and must not call Zenoh; they only push into
a mailbox. ``latest_only`` mailboxes keep the newest items (right for clouds
and state streams); the others keep every item up to a bound and count what
they had to drop, so overload is visible rather than silent.
"""

from __future__ import annotations

import threading
from collections import deque
from typing import Any

_CLOSED = object()


class Mailbox:
    def __init__(self, capacity: int) -> None:
        self._items: deque[Any] = deque(maxlen=capacity)
        self._cond = threading.Condition()
        self._closed = False
        self.dropped = 0

    def push(self, item: Any) -> None:
        with self._cond:
            if self._closed:
                return
            if len(self._items) == self._items.maxlen:
                self.dropped += 1
            self._items.append(item)
            self._cond.notify()

    def pop(self) -> Any:
        """Next item, or the ``CLOSED`` marker once closed and drained."""
        with self._cond:
            while not self._items and not self._closed:
                self._cond.wait()
            if self._items:
                return self._items.popleft()
            return _CLOSED

    def close(self) -> None:
        with self._cond:
            self._closed = True
            self._items.clear()
            self._cond.notify_all()


CLOSED = _CLOSED
