"""Zenoh's own records land in a service's log, as plain text."""

from __future__ import annotations

from pathlib import Path

from hfpbd.spawn import spawn_service
from shared.config import free_port
from tests.waiting import eventually


def _zenoh_warnings(log: str) -> list[str]:
    return [line for line in log.splitlines() if "zenoh::" in line and " WARN " in line]


def test_zenohs_warning_reaches_the_service_log(tmp_path: Path) -> None:
    # Nothing listens on this port: Zenoh warns that its start conditions were not met.
    session = ["--namespace", "tlogs", "--connect", f"tcp/127.0.0.1:{free_port()}", "--no-multicast-scouting"]
    service = spawn_service("nlu", session, tmp_path / "nlu.log")
    try:
        eventually(
            lambda: _zenoh_warnings(service.log()) or service.exited() is not None, 30, "a Zenoh warning or an exit"
        )
        log = service.log()
    finally:
        service.stop()
    assert _zenoh_warnings(log), f"no Zenoh warning in the log:\n{log[-2000:]}"
    assert "\x1b[" not in log, "colour codes in a log file"
