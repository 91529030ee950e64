"""``hfpbd nlu parse|ground|describe`` as a real subprocess on real files."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from tests.nlu.scenes import table_scene
from tests.processes import ROOT

HFPBD = str(ROOT / ".venv" / "bin" / "hfpbd")


def hfpbd(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([HFPBD, "nlu", *args], capture_output=True, text=True, timeout=60, cwd=ROOT)


@pytest.fixture
def world_file(tmp_path: Path) -> Path:
    path = tmp_path / "world.json"
    path.write_text(json.dumps(table_scene()))
    return path


def test_parse_prints_the_command(world_file: Path) -> None:
    done = hfpbd("parse", "--world", str(world_file), "move your right hand above the red cup")
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    assert (result["kind"], result["procedure"]) == ("command", "move_rel_dest")
    assert result["args"] == {"arm": "right", "relation": "above", "object": "obj0"}


def test_parse_batch_one_line_per_input(world_file: Path, tmp_path: Path) -> None:
    batch = tmp_path / "lines.txt"
    batch.write_text("up\npick up the cup\nxyzzy\n")
    done = hfpbd("parse", "--world", str(world_file), "--batch", str(batch))
    assert done.returncode == 0, done.stderr
    results = [json.loads(line) for line in done.stdout.splitlines()]
    assert [r["kind"] for r in results] == ["command", "clarify", "clarify"]
    assert results[1]["params"] == ["object"] and results[2]["params"] == []


def test_batch_carries_then_answers_and_refusals(world_file: Path, tmp_path: Path) -> None:
    batch = tmp_path / "lines.txt"
    lines = ["put the red cup on the plate", "what do you see", "move up 5 cm", "move up 50 cm", "x" * 10000]
    batch.write_text("\n".join(lines) + "\n")
    done = hfpbd("parse", "--world", str(world_file), "--batch", str(batch))
    assert done.returncode == 0, done.stderr
    placed, seen, moved, too_far, pasted = (json.loads(line) for line in done.stdout.splitlines())
    assert placed["procedure"] == "pick_up" and placed["then"][0]["procedure"] == "place_rel"
    assert seen["kind"] == "answer" and seen["topic"] == "scene"
    assert moved["args"]["distance"] == 0.05
    assert too_far["kind"] == "clarify" and too_far["params"] == ["distance"]
    assert pasted["kind"] == "clarify" and "too long" in pasted["question"]


def test_ground_and_describe(world_file: Path, tmp_path: Path) -> None:
    grounded = json.loads(hfpbd("ground", "--world", str(world_file), "the red cup").stdout)
    assert max(grounded, key=grounded.get) == "obj0" and sum(grounded.values()) == pytest.approx(1, abs=1e-3)
    batch = tmp_path / "phrases.txt"
    batch.write_text("the box\nthe leftmost cup\n")
    lines = hfpbd("ground", "--world", str(world_file), "--batch", str(batch)).stdout.splitlines()
    assert [max(m, key=m.get) for m in map(json.loads, lines)] == ["obj2", "obj1"]
    described = json.loads(hfpbd("describe", "--world", str(world_file)).stdout)
    assert described == {
        "obj0": "the rightmost cup",
        "obj1": "the leftmost cup",
        "obj2": "the box",
        "obj3": "the plate",
    }


@pytest.mark.parametrize(
    "content, message",
    [
        (None, "cannot read world file"),
        ("{not json", "is not valid JSON"),
        ('{"objects": 3}', "world 'objects' must be a list"),
        (
            '{"objects": [{"id": "a", "color": "red", "type": "cup", "position": [1, 2], "size": [0.1, 0.1, 0.1]}]}',
            "object 'a' position must be a list of three numbers",
        ),
        (
            '{"objects": [{"id": "a", "color": "mauve", "type": "cup", "position": [1, 2, 3], "size": [0.1, 0.1, 0.1]}]}',
            "object 'a' color must be one of",
        ),
        ('{"objects": [], "robot": {"last_object": "obj9"}}', "robot.last_object 'obj9' is not one of the objects"),
        ('{"objects": [], "robot": {"steps": [1, 2]}}', "robot.steps must be a list of the current action's steps"),
    ],
)
def test_bad_world_file_is_one_line_and_nonzero(tmp_path: Path, content: str | None, message: str) -> None:
    path = tmp_path / "world.json"
    if content is not None:
        path.write_text(content)
    done = hfpbd("parse", "--world", str(path), "up")
    assert done.returncode != 0
    assert done.stdout == ""
    assert len(done.stderr.strip().splitlines()) == 1 and message in done.stderr
    assert "Traceback" not in done.stderr


@pytest.mark.parametrize("args", [("parse", "--world"), ("parse", "--bogus", "x"), ("ground",)])
def test_bad_flags_are_one_line_and_nonzero(args: tuple[str, ...]) -> None:
    done = hfpbd(*args)
    assert done.returncode == 2
    assert len(done.stderr.strip().splitlines()) == 1 and "error" in done.stderr


def test_missing_batch_file(world_file: Path, tmp_path: Path) -> None:
    done = hfpbd("parse", "--world", str(world_file), "--batch", str(tmp_path / "absent.txt"))
    assert done.returncode == 1 and "cannot read batch file" in done.stderr


def test_benchmark_prints_its_table() -> None:
    done = subprocess.run(
        [HFPBD, "bench", "nlu", "--rounds", "20", "--sizes", "1", "4", "--batch-lines", "100"],
        capture_output=True,
        text=True,
        timeout=240,
        cwd=ROOT,
    )
    assert done.returncode == 0, done.stderr
    rows = [
        fields
        for fields in (line.split() for line in done.stdout.splitlines())
        if len(fields) >= 6 and fields[0].isdigit()
    ]
    assert [row[0] for row in rows] == ["1", "4"]
    assert "parse p99 target" in done.stdout and ("PASS" in done.stdout or "MISS" in done.stdout)
    accuracy = {
        line.split()[0]: line.split()[3]
        for line in done.stdout.splitlines()
        if line.endswith("%") or "(>= 97%)" in line
    }
    assert {"paper", "held", "relational", "compound", "distance", "questions", "typos", "all"} <= set(accuracy)
    assert [line.split()[1] for line in done.stdout.splitlines() if line.startswith("  batch,")] == ["4", "16", "64"]
