"""``hfpbd perception``: run the perception service."""

from __future__ import annotations

import argparse
import threading
from collections.abc import Sequence

from services.perception.pipeline import Settings
from services.perception.segment import SegmentSettings
from services.perception.service import PerceptionService
from services.perception.tracking import TrackSettings
from shared.bus import Bus
from shared.service import run_service, wait_until_stopped

DESCRIPTION = (
    "Object descriptors (position, size, colour and type words, stable ids) from the head camera's point clouds."
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("perception")
    group.add_argument(
        "--forget-after",
        type=float,
        default=TrackSettings.forget_after,
        metavar="SECONDS",
        help="drop an object unseen for this long (default: %(default)s)",
    )
    group.add_argument(
        "--confirm-frames",
        type=int,
        default=TrackSettings.confirm_frames,
        metavar="N",
        help="consecutive sightings before a new object gets an id (default: %(default)s)",
    )
    group.add_argument(
        "--max-jump",
        type=float,
        default=TrackSettings.max_jump,
        metavar="METRES",
        help="how far an object may move between frames and keep its id (default: %(default)s)",
    )
    group.add_argument(
        "--cell",
        type=float,
        default=SegmentSettings.cell,
        metavar="METRES",
        help="top-down grid cell; at most half the smallest gap between objects (default: %(default)s)",
    )
    group.add_argument(
        "--record-timeout",
        type=float,
        default=5.0,
        metavar="SECONDS",
        help="how long a record request waits for a settled view (default: %(default)s)",
    )


def body(bus: Bus, args: argparse.Namespace, stop: threading.Event) -> None:
    settings = Settings(segment=SegmentSettings(cell=args.cell))
    tracking = TrackSettings(
        forget_after=args.forget_after, confirm_frames=max(1, args.confirm_frames), max_jump=args.max_jump
    )
    service = PerceptionService(bus, settings, tracking, record_timeout=args.record_timeout)
    service.start()
    bus.declare_alive("perception")
    wait_until_stopped(stop)
    service.stop()


def main(argv: Sequence[str] | None = None) -> int:
    return run_service("perception", DESCRIPTION, body, argv, add_arguments)
