"""What `hfpbd up` starts when told nothing: every service, speech included (hands-free from the first command)."""

from __future__ import annotations

import subprocess
import sys

from hfpbd.launcher import SERVICES


def test_speech_is_among_the_services_started_by_default() -> None:
    assert "speech" in SERVICES
    shown = subprocess.run(
        [sys.executable, "-m", "hfpbd.launcher", "--help"], capture_output=True, text=True, timeout=60, check=True
    ).stdout
    assert "default: sim,perception,nlu,executor,speech" in " ".join(shown.split())
