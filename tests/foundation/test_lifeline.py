"""``hfpbd.lifeline``: a child runs its module, and ends when its parent is gone."""

from __future__ import annotations

import signal
import subprocess
import sys

from tests.processes import ROOT


def test_a_child_whose_parent_is_already_gone_ends_at_once() -> None:
    # PID 1 is never this test's process: the child sees another parent than the one named and ends
    result = subprocess.run(
        [sys.executable, "-m", "hfpbd.lifeline", "1", "-m", "tests.echo_peer"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert result.returncode == -signal.SIGTERM and "echo up" not in result.stderr


PARENT = (
    "import os, subprocess, sys; sys.exit(subprocess.run([sys.executable, '-m', 'hfpbd.lifeline', "
    "str(os.getpid()), '-m', 'hfpbd.cli', 'version']).returncode)"
)


def test_the_module_runs_with_its_own_arguments() -> None:
    result = subprocess.run(
        [sys.executable, "-c", PARENT], cwd=ROOT, capture_output=True, text=True, timeout=60, check=False
    )
    assert result.returncode == 0 and result.stdout.startswith("hfpbd ")


def test_bad_usage_is_one_line() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "hfpbd.lifeline", "nlu"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert result.returncode == 1 and result.stderr.startswith("usage: python -m hfpbd.lifeline")
