"""``hfpbd nlu parse|ground|describe``: the model on world files, one JSON per line.

Errors (bad world file, missing batch file, bad flags) are one line on
stderr and a non-zero exit; an utterance nobody understands is a normal
``clarify`` answer, not an error.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable, Iterable, Sequence
from typing import Any

from services.nlu.infer import Model
from services.nlu.world import WorldError, load_world

TOOLS = ("parse", "ground", "describe")


class _Parser(argparse.ArgumentParser):
    """argparse that reports a bad flag in one line."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message}\n")


def main(argv: Sequence[str]) -> int:
    tool, rest = argv[0], list(argv[1:])
    parser = _Parser(prog=f"hfpbd nlu {tool}", description=_DESCRIPTIONS[tool])
    parser.add_argument("--world", required=True, help="world-state JSON file (objects and robot)")
    if tool != "describe":
        source = parser.add_mutually_exclusive_group(required=True)
        source.add_argument("text", nargs="?", help="the utterance or referring phrase")
        source.add_argument(
            "--batch", metavar="FILE", help="one input per line ('-' for stdin); one JSON line out per line"
        )
    args = parser.parse_args(rest)
    try:
        model = Model(load_world(args.world))
    except WorldError as exc:
        print(f"hfpbd nlu {tool}: {exc}", file=sys.stderr)
        return 1
    if tool == "describe":
        _emit(model.describe())
        return 0
    answer: Callable[[str], Any] = (lambda text: model.parse(text).to_json()) if tool == "parse" else model.ground
    if args.batch is None:
        _emit(answer(args.text))
        return 0
    try:
        lines = _lines(args.batch)
        for line in lines:
            _emit(answer(line))
    except OSError as exc:
        print(f"hfpbd nlu {tool}: cannot read batch file {args.batch!r}: {exc.strerror or exc}", file=sys.stderr)
        return 1
    return 0


def _lines(path: str) -> Iterable[str]:
    handle = sys.stdin if path == "-" else open(path, encoding="utf-8", errors="replace")
    with handle:
        for line in handle:
            yield line.rstrip("\n")


def _emit(value: Any) -> None:
    sys.stdout.write(json.dumps(value) + "\n")


_DESCRIPTIONS = {
    "parse": "Understand an utterance in a world: print the command or the clarification question as JSON.",
    "ground": "Print the probability of each object being the one a referring phrase means.",
    "describe": "Print the generated referring expression of every object.",
}
