"""The access-denial filter on a process's real standard output: denials become one warning, the rest passes."""

from __future__ import annotations

import subprocess
import sys

from tests.processes import ROOT

# Lines as Zenoh 1.10.2 writes them (colours aside): a verdict naming the subject, a cached verdict naming
# only the session id, and the forecast Zenoh logs for every kind of message when a key expression is declared.
SCRIPT = r"""
import logging, os, sys, threading
logging.basicConfig(level=logging.INFO, format="%(name)s: %(message)s")
before = os.fstat(1)
from shared.denials import log_access_denials, unfiltered_stdout
log_access_denials()
real, now = os.fstat(unfiltered_stdout()), os.fstat(1)
head = "2026-01-01T00:00:00Z TRACE rx-0 zenoh::net::routing::interceptor::access_control: "
operator = "1f2e3d4c on Interface(lo)+CertCommonName(operator)+Transport(Tls)+1f2e3d4c"
denied = head + operator + " is unauthorized to Put (ingress) on pbd/x/sim/state\n"
cached = head + "Using cached result: 1f2e3d4c is unauthorized to Put (ingress) on pbd/x/sim/state\n"
allowed = (head + "9a8b7c6d on Interface(lo)+CertCommonName(robot)+Transport(Tls)+9a8b7c6d is authorized to Put "
           "(ingress) on pbd/x/sim/state\n")
forecast = [head + "ACL (ingress): caching permissions for `pbd/x/dialog/say` ...\n"] + [
    head + operator + " is unauthorized to " + kind + " (ingress) on pbd/x/dialog/say\n"
    for kind in ("Query", "Put", "Delete")]
for line in [*forecast, denied, allowed, cached, "an ordinary line\n", denied]:
    os.write(1, line.encode())
print("terminal kept:", (real.st_dev, real.st_ino) == (before.st_dev, before.st_ino), now.st_ino != before.st_ino)
sys.stdout.flush()
os.dup2(os.open(os.devnull, os.O_WRONLY), 1)  # the filter's pipe is closed: it passes on what is left and ends
next(t for t in threading.enumerate() if t.name == "access-denials").join(10)
"""


def test_denials_are_reported_once_and_other_output_passes_unchanged() -> None:
    result = subprocess.run(
        [sys.executable, "-c", SCRIPT], cwd=ROOT, capture_output=True, text=True, timeout=60, check=False
    )
    assert result.returncode == 0, result.stderr
    assert result.stderr.count("hfpbd.access: refused operator: put on pbd/x/sim/state") == 1, result.stderr
    assert "dialog/say" not in result.stderr, "a forecast made when a key is declared is not a refusal"
    assert "an ordinary line" in result.stdout and "terminal kept: True True" in result.stdout
    assert "authorized" not in result.stdout and "access_control" not in result.stdout
