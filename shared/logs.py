"""Logging convention: one line per record, service name first, to stderr.

``HFPBD_LOG`` (debug, info, warning) sets the level. Zenoh's own records
(warnings by default, its info too at debug; ``RUST_LOG`` overrides) go to
the process's output too, so a service's log file holds both: a refused TLS
handshake or a dropped link shows up where the service's own lines are.
Colour codes are turned off unless stderr is a terminal, so log files stay
plain text. Zenoh's log can be set up once per process only, so
:func:`init_zenoh_log` is the one place that does it.
"""

from __future__ import annotations

import logging
import os
import sys
import threading

import zenoh

ACL_TARGET = "zenoh::net::routing::interceptor::access_control"
_zenoh_log_started = threading.Lock()


def _level() -> str:
    return os.environ.get("HFPBD_LOG", "info").upper()


def init_zenoh_log() -> None:
    """Turn on Zenoh's log for this process (once; later calls do nothing).

    The access control's verdicts are traced too: only a session that
    enforces access control writes them, and that session reads them back
    (``shared.denials``) to report what it refused.
    """
    if not _zenoh_log_started.acquire(blocking=False):
        return
    # Zenoh reads NO_COLOR once, here; the variable is put back so that nothing else in this process (a
    # terminal UI) loses its colours
    before = os.environ.get("NO_COLOR")
    if not sys.stderr.isatty():
        os.environ["NO_COLOR"] = "1"
    try:
        zenoh.init_log_from_env_or(f"{'info' if _level() == 'DEBUG' else 'warn'},{ACL_TARGET}=trace")
    finally:
        if before is None:
            os.environ.pop("NO_COLOR", None)
        else:
            os.environ["NO_COLOR"] = before


def setup_logging(service: str) -> None:
    logging.basicConfig(
        level=getattr(logging, _level(), logging.INFO),
        stream=sys.stderr,
        format=f"%(asctime)s {service} %(levelname)s %(name)s: %(message)s",
    )
    init_zenoh_log()
