"""Logging convention: one line per record, service name first, to stderr.

``HFPBD_LOG`` (debug, info, warning) sets the level; Zenoh's own logging
follows ``RUST_LOG`` as usual.
"""

from __future__ import annotations

import logging
import os
import sys


def setup_logging(service: str) -> None:
    level = os.environ.get("HFPBD_LOG", "info").upper()
    logging.basicConfig(
        level=getattr(logging, level, logging.INFO),
        stream=sys.stderr,
        format=f"%(asctime)s {service} %(levelname)s %(name)s: %(message)s",
    )
