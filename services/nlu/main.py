"""``hfpbd nlu``: the service, or a tool word (parse, ground, describe)."""

from __future__ import annotations

import sys
from collections.abc import Sequence

from services.nlu import cli


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    if args and args[0] in cli.TOOLS:
        return cli.main(args)
    from services.nlu.service import run  # the bus only when running as a service

    return run(args)
