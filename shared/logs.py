"""Logging convention: one line per record, service name first, to stderr.

``HFPBD_LOG`` (debug, info, warning) sets the level. Zenoh's own records
(warnings by default, its info too at debug; ``RUST_LOG`` overrides) go to
the same stderr, so a service's log file holds both: a refused TLS handshake
or a dropped link shows up where the service's own lines are. Colour codes
are turned off unless stderr is a terminal, so log files stay plain text.
"""

from __future__ import annotations

import logging
import os
import sys

import zenoh


def setup_logging(service: str) -> None:
    level = os.environ.get("HFPBD_LOG", "info").upper()
    logging.basicConfig(
        level=getattr(logging, level, logging.INFO),
        stream=sys.stderr,
        format=f"%(asctime)s {service} %(levelname)s %(name)s: %(message)s",
    )
    if not sys.stderr.isatty():
        os.environ.setdefault("NO_COLOR", "1")
    zenoh.init_log_from_env_or("info" if level == "DEBUG" else "warn")
