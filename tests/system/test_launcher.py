"""``hfpbd up``: supervision restarts a crashed service; stopping leaves no orphans."""

from __future__ import annotations

import queue
import signal
import subprocess
import sys
import time
import uuid
from pathlib import Path

import psutil
import pytest

from shared.bus import Bus
from shared.config import free_port, loopback_options
from tests.processes import ROOT


def _wait(predicate, timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.2)
    return False


@pytest.fixture
def robot(tmp_path: Path):
    """``hfpbd up --headless`` with the NLU only, on a private port and namespace."""
    namespace, port = "up" + uuid.uuid4().hex[:8], free_port()
    popen = subprocess.Popen(
        [sys.executable, "-m", "hfpbd.launcher", "--headless", "--services", "nlu", "--namespace", namespace,
         "--listen", f"tcp/127.0.0.1:{port}", "--log-dir", str(tmp_path)],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    bus = Bus(loopback_options(namespace, port, listen=False))
    try:
        yield popen, bus
    finally:
        bus.close()
        if popen.poll() is None:
            popen.kill()
            popen.wait(10)
        for child in psutil.process_iter(["cmdline"]):
            if namespace in " ".join(child.info["cmdline"] or []):
                child.kill()


def test_crashed_service_is_reported_and_restarted_and_stop_leaves_no_orphans(robot) -> None:
    popen, bus = robot
    said: queue.Queue = queue.Queue()
    bus.subscribe(bus.keys.say, said.put, schema="say")
    assert _wait(lambda: "nlu" in bus.alive_services(), 60), "the NLU never came up"
    nlu = psutil.Process(popen.pid).children()[0]
    nlu.kill()
    message = said.get(timeout=20)
    assert message["kind"] == "error" and "nlu service stopped" in message["text"] and "restarting" in message["text"]
    assert _wait(lambda: "nlu" in bus.alive_services() and
                 any(c.pid != nlu.pid for c in psutil.Process(popen.pid).children()), 60)
    children = psutil.Process(popen.pid).children(recursive=True)
    popen.send_signal(signal.SIGINT)
    assert popen.wait(30) == 0
    assert _wait(lambda: not any(c.is_running() and c.status() != psutil.STATUS_ZOMBIE for c in children), 15)


def test_unknown_service_is_refused(tmp_path: Path) -> None:
    result = subprocess.run([sys.executable, "-m", "hfpbd.launcher", "--headless", "--services", "nlu,teleporter"],
                            cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert result.returncode != 0 and "unknown service(s) teleporter" in result.stderr
