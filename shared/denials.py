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

from shared.logs import ACL_TARGET, init_zenoh_log

log = logging.getLogger("hfpbd.access")

REPEAT_S = 10.0  # a repeated denial is counted, and reported again at most this often
_PERMISSION = re.compile(
    r"(?P<zid>[0-9a-f]{8,}) (?:on (?P<subject>\S+) )?is (?P<verdict>un)?authorized to "
    r"(?P<what>.+?) \((?P<flow>\w+)\) on (?P<key>\S+)"
)
_COMMON_NAME = re.compile(r"CertCommonName\((?P<name>[^)]*)\)")
_CACHING = re.compile(r"caching permissions for `(?P<key>[^`]+)`")
_started = threading.Lock()
_terminal: list[int] = []  # this process's own standard output, once it is filtered


class _Reporter:
    """Turns denial lines into warnings, at most one per (who, what, key) every ``REPEAT_S`` seconds.

    When a key expression is declared, Zenoh works out every kind of message
    on it at once and logs each verdict after a "caching permissions for
    `KEY`" line: those are forecasts, not messages, and are skipped (one line
    per kind; a kind seen twice means a real message).
    """

    def __init__(self) -> None:
        self._last: dict[tuple[str, str, str], tuple[float, int]] = {}
        self._forecast: tuple[str, set[str]] | None = None
        self._names: dict[str, str] = {}  # session id -> certificate common name (cached verdicts give only the id)

    def line(self, text: str) -> bool:
        """Handle one line of Zenoh's log; False when it is not the access control's."""
        if ACL_TARGET.rsplit("::", 1)[-1] not in text:
            return False
        caching = _CACHING.search(text)
        if caching is not None:
            self._forecast = (caching["key"], set())
            return True
        match = _PERMISSION.search(text)
        if match is None:
            self._forecast = None
            return True  # bookkeeping: dropped
        what, key = match["what"].lower(), match["key"]
        name = _COMMON_NAME.search(match["subject"] or "")
        if name is not None:
            self._names[match["zid"]] = name["name"]
        if self._forecast is not None and self._forecast[0] == key and what not in self._forecast[1]:
            self._forecast[1].add(what)
            return True
        self._forecast = None
        if match["verdict"]:
            self._report(self._names.get(match["zid"], f"session {match['zid']}"), what, key)
        return True

    def _report(self, who: str, what: str, key: str) -> None:
        now = time.monotonic()
        last, count = self._last.get((who, what, key), (float("-inf"), 0))
        if now - last >= REPEAT_S:
            more = f" ({count} more since the last report)" if count else ""
            log.warning("refused %s: %s on %s%s", who, what, key, more)
            self._last[(who, what, key)] = (now, 0)
        else:
            self._last[(who, what, key)] = (last, count + 1)


def _pump(read_fd: int, out_fd: int, reporter: _Reporter) -> None:
    with os.fdopen(read_fd, "rb", buffering=0) as pipe, os.fdopen(out_fd, "wb", buffering=0) as out:
        pending = b""
        while chunk := pipe.read(65536):
            pending += chunk
            *lines, pending = pending.split(b"\n")
            for raw in lines:
                if not reporter.line(raw.decode("utf-8", "replace")):
                    out.write(raw + b"\n")


def unfiltered_stdout() -> int:
    """The file descriptor of the real standard output, for a child that needs the terminal itself (the TUI)."""
    return _terminal[0] if _terminal else 1


def log_access_denials() -> None:
    """Start reporting access-control denials of this process's Zenoh sessions (once per process).

    Whatever else this process prints passes through unchanged.
    """
    if not _started.acquire(blocking=False):
        return
    sys.stdout.flush()
    original = os.dup(1)
    _terminal.append(os.dup(original))
    read_fd, write_fd = os.pipe()
    os.dup2(write_fd, 1)
    os.close(write_fd)
    reporter = _Reporter()
    threading.Thread(target=_pump, args=(read_fd, original, reporter), name="access-denials", daemon=True).start()
    init_zenoh_log()
