"""The ``hfpbd`` command: one subcommand per service, plus up, bench and version.

Subcommands are resolved lazily so ``hfpbd tui`` never imports SAPIEN and a
missing or broken service only affects its own subcommand.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Sequence
from importlib.metadata import PackageNotFoundError, version

# subcommand -> module with main(argv) -> int, and a one-line summary
COMMANDS: dict[str, tuple[str, str]] = {
    "sim": ("services.sim.main", "physically simulated PR2 at a table (SAPIEN)"),
    "perception": ("services.perception.main", "object descriptors from point clouds"),
    "nlu": ("services.nlu.main", "situated language understanding (service, parse, ground, describe)"),
    "executor": ("services.executor.main", "runs procedures, records and replays actions"),
    "tui": ("tui.main", "terminal user interface for the programming dialog"),
    "speech": ("services.speech.main", "spoken commands in, spoken feedback out"),
    "up": ("hfpbd.launcher", "start every service on this machine and supervise them"),
    "bench": (
        "hfpbd.bench",
        "benchmarks: bus, nlu, sim, perception, executor, manipulation, skills, tasks, speech, fuzz",
    ),
    "secure": ("hfpbd.secure", "certificates for secure remote operation ('hfpbd secure init DIR')"),
}


def _usage() -> str:
    lines = ["usage: hfpbd COMMAND [ARGS...]", "", "commands:"]
    for name, (_, summary) in COMMANDS.items():
        lines.append(f"  {name:<11} {summary}")
    lines.append(f"  {'version':<11} print the version")
    lines.append("")
    lines.append("Run 'hfpbd COMMAND --help' for the flags of one command.")
    return "\n".join(lines)


def project_version() -> str:
    try:
        return version("handsfree-pbd")
    except PackageNotFoundError:
        return "unknown"


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    if not args or args[0] in ("-h", "--help", "help"):
        print(_usage())
        return 0 if args else 2
    command, rest = args[0], args[1:]
    if command in ("version", "--version"):
        print(f"hfpbd {project_version()}")
        return 0
    if command not in COMMANDS:
        print(f"hfpbd: unknown command {command!r}\n\n{_usage()}", file=sys.stderr)
        return 2
    module_name = COMMANDS[command][0]
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        if exc.name and module_name.startswith(exc.name):
            print(f"hfpbd: '{command}' is not available in this version yet", file=sys.stderr)
            return 3
        raise
    return int(module.main(rest) or 0)


if __name__ == "__main__":
    sys.exit(main())
