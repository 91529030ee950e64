"""Waiting in tests: for a condition, or for Zenoh to report that a peer can be reached.

A test never sleeps a fixed time: it waits for the event the sleep stood
for. ``eventually`` is the one place that polls; the Zenoh waits ask Zenoh
itself whether a subscriber or a queryable on a key is known to a session.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TypeVar

from shared.bus import Bus

T = TypeVar("T")

# Short enough that a met condition is seen at once, long enough not to starve the code under test.
POLL_SECONDS = 0.02


def eventually(condition: Callable[[], T], timeout: float = 10.0, what: str = "") -> T:
    """The first truthy value of ``condition()``; fail with ``what`` after ``timeout`` seconds."""
    deadline = time.monotonic() + timeout
    while True:
        value = condition()
        if value:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout:g} s waiting for {what or condition}")
        time.sleep(POLL_SECONDS)


def subscribed(bus: Bus, key: str, timeout: float = 10.0) -> None:
    """Wait until ``bus`` knows a subscriber on ``key``: a sample put from it now is routed there."""
    publisher = bus.session.declare_publisher(key)
    try:
        eventually(lambda: publisher.matching_status.matching, timeout, f"a subscriber on {key}")
    finally:
        publisher.undeclare()


def served(bus: Bus, key: str, timeout: float = 10.0) -> None:
    """Wait until ``bus`` knows a queryable on ``key``: a request from it now reaches the service."""
    querier = bus.session.declare_querier(key)
    try:
        eventually(lambda: querier.matching_status.matching, timeout, f"a queryable on {key}")
    finally:
        querier.undeclare()
