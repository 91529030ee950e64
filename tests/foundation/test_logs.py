"""Zenoh's own records land in a service's log, as plain text."""

from __future__ import annotations

import time
from pathlib import Path

from hfpbd.spawn import spawn_service
from shared.config import free_port


def test_zenohs_warning_reaches_the_service_log(tmp_path: Path) -> None:
    # Nothing listens on this port: Zenoh warns that its start conditions were not met.
    session = ["--namespace", "tlogs", "--connect", f"tcp/127.0.0.1:{free_port()}", "--no-multicast-scouting"]
    service = spawn_service("nlu", session, tmp_path / "nlu.log")
    try:
        deadline = time.monotonic() + 30
        while "zenoh::" not in service.log() and time.monotonic() < deadline and service.exited() is None:
            time.sleep(0.2)
        log = service.log()
    finally:
        service.stop()
    zenoh_lines = [line for line in log.splitlines() if "zenoh::" in line]
    assert zenoh_lines, f"no Zenoh record in the log:\n{log[-2000:]}"
    assert "WARN" in zenoh_lines[0]
    assert "\x1b[" not in log, "colour codes in a log file"
