"""``hfpbd tui``: the terminal UI, on this machine or against a remote robot.

hfpbd tui                                  # services on this machine (multicast)
hfpbd tui --connect tcp/robot-host:7447    # a robot elsewhere
hfpbd tui --connect tls/robot-host:7447 --secure DIR   # the same, as the operator, over mutual TLS
"""

from __future__ import annotations

import argparse
import logging
from collections.abc import Sequence

from shared.config import add_session_arguments, options_from_args

# the drawing methods' names, without importing textual-image (which asks the terminal what it can draw)
DRAWINGS = ("auto", "halfcell", "sixel", "tgp")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="hfpbd tui", description="Program the robot by talking to it, in a terminal.")
    add_session_arguments(parser, default_identity="operator")
    parser.add_argument(
        "--probe-seconds",
        type=float,
        default=2.0,
        metavar="S",
        help="how often to measure latency to the services; 0 turns it off (default: %(default)s)",
    )
    parser.add_argument(
        "--camera-drawing",
        choices=sorted(DRAWINGS),
        default="auto",
        help="how camera pictures are drawn: a terminal graphics protocol (sixel, tgp), coloured "
        "half-blocks (halfcell), or the best the terminal offers (default: %(default)s)",
    )
    parser.add_argument(
        "--log-file", metavar="FILE", help="write the UI's log here (the terminal itself belongs to the UI)"
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        options = options_from_args(args)
    except ValueError as exc:
        parser.error(str(exc))
    # Log lines on stderr would tear the screen; they go to a file or nowhere.
    if args.log_file:
        logging.basicConfig(
            filename=args.log_file, level=logging.INFO, format="%(asctime)s tui %(levelname)s %(name)s: %(message)s"
        )
    else:
        logging.getLogger().addHandler(logging.NullHandler())
    from tui.app import PbdApp  # Textual is imported only when the UI really starts

    PbdApp(options, probe_seconds=args.probe_seconds or None, camera_drawing=args.camera_drawing).run()
    return 0
