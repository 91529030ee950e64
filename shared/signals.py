"""Signals that end a process set an event, from a thread of their own, never inside a signal handler.

Why not ``stop.set()`` in the handler: Python runs a handler in the main
thread between any two bytecodes, also while that thread holds the event's
lock (inside ``stop.wait()``, or inside the handler of the signal before).
A handler that then takes the lock waits for itself for ever: a service
sent SIGTERM twice in a row (its parent dying, and the launcher stopping
it) hung that way instead of stopping. Here the handler does nothing in
Python; the interpreter's C handler writes the signal's number to a pipe
(``signal.set_wakeup_fd``), and a thread reading the pipe logs it and sets
the event.
"""

from __future__ import annotations

import logging
import os
import signal
import threading
from collections.abc import Iterable


def stop_on(signals: Iterable[signal.Signals], stop: threading.Event, log: logging.Logger, message: str) -> None:
    """Set ``stop`` when any of ``signals`` arrives, logging ``message`` with the signal's name (call from main)."""
    read_end, write_end = os.pipe()
    os.set_blocking(write_end, False)
    signal.set_wakeup_fd(write_end, warn_on_full_buffer=False)
    for signum in signals:
        signal.signal(signum, _noted_by_the_wakeup_pipe)

    def watch() -> None:
        while numbers := os.read(read_end, 64):
            for number in numbers:
                log.info(message, signal.Signals(number).name)
            stop.set()

    threading.Thread(target=watch, name="signals", daemon=True).start()


def ignore_from_now(signals: Iterable[signal.Signals]) -> None:
    """Ignore ``signals`` for the rest of the process (call from main, once stopping is under way).

    Why: while Python shuts down it puts back the default action of every
    signal it had a handler for, so a signal of a burst still arriving then
    (a parent dying as the launcher stops it) would end a cleanly stopped
    process with that signal's status. An ignored signal is left ignored.
    """
    for signum in signals:
        signal.signal(signum, signal.SIG_IGN)


def _noted_by_the_wakeup_pipe(_signum: int, _frame: object) -> None:
    """The Python-level handler: nothing to do, the number is already in the pipe."""
