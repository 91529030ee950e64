"""Log what the access control drops: one warning per identity, message kind and key, then a count.

Why this detour: Zenoh drops a message its access control forbids and says
so only in its own trace log, next to a line for every message it lets
through. A robot host must still tell its person that the operator laptop
tried to load a scene, so this process's output goes through a filter:
Zenoh's denial lines become short warnings on the ``hfpbd.access`` logger,
its "authorized" lines are dropped, and every other line passes unchanged.
Zenoh's log (Rust's ``tracing``) writes to standard output, so that is the
stream filtered.
"""

from __future__ import annotations

import logging
import os
import re
import sys
import threading
import time

import zenoh

log = logging.getLogger("hfpbd.access")

ACL_TARGET = "zenoh::net::routing::interceptor::access_control"
REPEAT_S = 10.0  # a repeated denial is counted, and reported again at most this often
_DENIAL = re.compile(r"CertCommonName\((?P<who>[^)]*)\).*? is unauthorized to (?P<what>.+?) \((?P<flow>\w+)\) "
                     r"on (?P<key>\S+)")
_started = threading.Lock()


class _Reporter:
    """Turns denial lines into warnings, at most one per (who, what, key) every ``REPEAT_S`` seconds."""

    def __init__(self) -> None:
        self._last: dict[tuple[str, str, str], tuple[float, int]] = {}

    def line(self, text: str) -> bool:
        """Handle one line of Zenoh's log; False when it is not the access control's."""
        if ACL_TARGET.rsplit("::", 1)[-1] not in text:
            return False
        match = _DENIAL.search(text)
        if match is None:
            return True  # an "authorized" or bookkeeping line: dropped
        who, what, key = match["who"], match["what"].lower(), match["key"]
        now = time.monotonic()
        last, count = self._last.get((who, what, key), (float("-inf"), 0))
        if now - last >= REPEAT_S:
            more = f" ({count} more since the last report)" if count else ""
            log.warning("refused %s: %s on %s%s", who or "an unnamed peer", what, key, more)
            self._last[(who, what, key)] = (now, 0)
        else:
            self._last[(who, what, key)] = (last, count + 1)
        return True


def _pump(read_fd: int, out_fd: int, reporter: _Reporter) -> None:
    with os.fdopen(read_fd, "rb", buffering=0) as pipe, os.fdopen(out_fd, "wb", buffering=0) as out:
        pending = b""
        while chunk := pipe.read(65536):
            pending += chunk
            *lines, pending = pending.split(b"\n")
            for raw in lines:
                if not reporter.line(raw.decode("utf-8", "replace")):
                    out.write(raw + b"\n")


def log_access_denials() -> None:
    """Start reporting access-control denials of this process's Zenoh sessions (once per process).

    Whatever else this process prints passes through unchanged.
    """
    if not _started.acquire(blocking=False):
        return
    sys.stdout.flush()
    original = os.dup(1)
    read_fd, write_fd = os.pipe()
    os.dup2(write_fd, 1)
    os.close(write_fd)
    reporter = _Reporter()
    threading.Thread(target=_pump, args=(read_fd, original, reporter), name="access-denials", daemon=True).start()
    zenoh.init_log_from_env_or(f"warn,{ACL_TARGET}=trace")
