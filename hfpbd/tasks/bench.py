"""``hfpbd bench tasks``: program the paper's five tasks in the three language styles and replay them.

By default the benchmark starts its own services (fresh namespace and port,
throw-away action store) so it never disturbs a running robot; ``--attach``
runs against services already up (``hfpbd up --headless``) on the session
flags given. Prints the table and the comparison with the paper, and writes
``tasks.md``, ``tasks.csv``, ``tasks.json`` (every step) and ``tasks.png``
(Fig. 6 style) into ``--out``.
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
import tempfile
import time
import uuid
from collections.abc import Sequence
from pathlib import Path

from hfpbd.tasks import figures
from hfpbd.tasks.runner import RunError, TaskRunner
from hfpbd.tasks.scripts import STYLES, ScriptError, load_tasks
from hfpbd.tasks.stack import LocalStack
from shared.bus import Bus
from shared.config import add_session_arguments, free_port, loopback_options, options_from_args

DESCRIPTION = (
    "Program the paper's five tasks in full, minimal and conversational language through the real services, "
    "judge them from ground truth, replay them on moved objects, and compare with the paper."
)


def _parse(argv: Sequence[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="hfpbd bench tasks", description=DESCRIPTION)
    parser.add_argument("--tasks", default="", help="comma-separated task ids (default: all)")
    parser.add_argument("--styles", default=",".join(STYLES), help="comma-separated styles (default: %(default)s)")
    parser.add_argument("--out", type=Path, default=Path("bench-results"), help="output folder (default: %(default)s)")
    parser.add_argument("--no-replay", action="store_true", help="program only; skip moving the objects and executing")
    parser.add_argument(
        "--attach",
        action="store_true",
        help="use services already running (session flags below) instead of starting private ones",
    )
    add_session_arguments(parser)
    return parser.parse_args(list(argv))


def main(argv: Sequence[str] | None = None) -> int:
    args = _parse(sys.argv[1:] if argv is None else argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s", datefmt="%H:%M:%S")
    try:
        book = load_tasks()
        tasks = [book.task(t.strip()) for t in args.tasks.split(",") if t.strip()] or list(book.tasks)
        styles = [s.strip() for s in args.styles.split(",") if s.strip()]
        for style in styles:
            tasks[0].script(style)
    except ScriptError as exc:
        print(f"hfpbd bench tasks: {exc}", file=sys.stderr)
        return 2
    args.out.mkdir(parents=True, exist_ok=True)
    try:
        runs = _run_all(args, tasks, styles)
    except (RunError, RuntimeError) as exc:
        print(f"hfpbd bench tasks: {exc}", file=sys.stderr)
        return 1
    _report(runs, book.paper, args.out)
    return 0


def _run_all(args: argparse.Namespace, tasks: list, styles: list[str]) -> list[dict]:
    if args.attach:
        with Bus(options_from_args(args)) as bus:
            return _run(TaskRunner(bus), tasks, styles, not args.no_replay)
    namespace, port = "bench" + uuid.uuid4().hex[:8], free_port()
    with Bus(loopback_options(namespace, port, listen=True)) as bus, tempfile.TemporaryDirectory() as data:
        session = loopback_options(namespace, port, listen=False).to_argv()
        stack = LocalStack(bus, args.out / "logs")
        try:
            started = time.monotonic()
            for name in ("sim", "perception", "nlu"):
                stack.start(name, session)
            stack.start("executor", session, "--data-dir", data)
            print(f"services up in {time.monotonic() - started:.1f} s (logs in {args.out / 'logs'})", flush=True)
            return _run(TaskRunner(bus), tasks, styles, not args.no_replay)
        finally:
            stack.stop()


def _run(runner: TaskRunner, tasks: list, styles: list[str], replay: bool) -> list[dict]:
    runner.wait_for_services()
    runs = []
    for task in tasks:
        for style in styles:
            report = runner.run(task, style, replay=replay)
            print(
                f"{task.id} {style}: success={report.success.success} ({report.success.reason}); "
                f"replay={report.replay.success} ({report.replay.reason})",
                flush=True,
            )
            runs.append(report.as_dict())
    return runs


def _report(runs: list[dict], paper: dict, out: Path) -> None:
    rows = figures.table_rows(runs)
    comparison = figures.comparison(runs, paper)
    print()
    print(figures.text_table(rows))
    print()
    print("Compared with the paper (section IV-E, Fig. 6); our times are the system's alone, with no typing:")
    for line in comparison:
        print("  " + line)
    (out / "tasks.json").write_text(json.dumps(runs, indent=1, default=str))
    figures.write_csv(rows, out / "tasks.csv")
    (out / "tasks.md").write_text(
        figures.markdown_table(rows) + "\n\n" + "\n".join(f"- {line}" for line in comparison) + "\n"
    )
    figures.chart(runs, out / "tasks.png")
    print(f"\nwrote {out / 'tasks.md'}, tasks.csv, tasks.json and tasks.png")
