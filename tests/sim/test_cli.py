"""``hfpbd sim snapshot`` and ``hfpbd sim scenes``: real processes, real files."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[2]


def hfpbd_sim(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "services.sim", *args], cwd=ROOT, capture_output=True, text=True, timeout=120
    )


def test_snapshot_writes_a_picture_of_the_scene(tmp_path: Path) -> None:
    out = tmp_path / "scene.png"
    result = hfpbd_sim("snapshot", "--scene", "task3_in_box", "--out", str(out))
    assert result.returncode == 0, result.stderr
    image = cv2.imread(str(out))
    assert image is not None and image.shape == (600, 800, 3)
    hsv = cv2.cvtColor(image, cv2.COLOR_BGR2HSV)
    yellow = (np.abs(hsv[..., 0].astype(int) - 27) < 6) & (hsv[..., 1] > 150)
    assert yellow.sum() > 30, "the yellow box is in the picture"


def test_snapshot_of_an_unknown_scene_is_a_one_line_error(tmp_path: Path) -> None:
    result = hfpbd_sim("snapshot", "--scene", "kitchen", "--out", str(tmp_path / "x.png"))
    assert result.returncode == 2
    assert "unknown scene 'kitchen'" in result.stderr and "Traceback" not in result.stderr
    assert not (tmp_path / "x.png").exists()


def test_scenes_lists_the_task_scenes() -> None:
    result = hfpbd_sim("scenes")
    assert result.returncode == 0
    assert "task4_large_box" in result.stdout and "refexp_4_cups" in result.stdout
