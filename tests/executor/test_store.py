"""The action store: atomic saves, reload after a restart or another writer, numbering rules."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from services.executor.actions_cli import apply_action_op
from services.executor.actions_cli import main as actions_main
from services.executor.store import FILE_NAME, ActionStore, StoreError, atomic_write_text

ROOT = Path(__file__).resolve().parents[2]
STEP = {
    "procedure": "pick_up",
    "args": {"arm": "right", "object": "obj0"},
    "utterance": "grab the red cup",
    "landmark": {"id": "obj0", "color": "red", "type": "cup", "size": [0.07, 0.07, 0.1], "position": [0.6, 0, 0.77]},
}


def test_steps_survive_a_restart(tmp_path: Path) -> None:
    store = ActionStore(tmp_path)
    assert store.create() == 1
    store.append_step(STEP)
    store.append_step({**STEP, "procedure": "place_abs", "args": {"arm": "right", "destination": "table"}})
    again = ActionStore(tmp_path)
    assert again.current == 1
    assert again.step_counts() == [2]
    assert again.get(1)["steps"][0]["utterance"] == "grab the red cup"


def test_first_step_without_an_action_creates_action_one(tmp_path: Path) -> None:
    store = ActionStore(tmp_path)
    assert store.append_step(STEP) == (1, 1)
    assert store.current == 1


def test_changes_by_another_writer_are_seen(tmp_path: Path) -> None:
    service = ActionStore(tmp_path)
    service.create()
    tool = ActionStore(tmp_path)
    tool.rename(1, "stack cups")
    tool.create()
    assert service.count() == 2
    assert service.summaries()[0]["name"] == "stack cups"


@pytest.mark.parametrize("current, deleted, expected", [(3, 1, 2), (3, 3, 2), (1, 2, 1), (2, 2, 2)])
def test_delete_keeps_the_current_action_in_step(tmp_path: Path, current: int, deleted: int, expected: int) -> None:
    store = ActionStore(tmp_path)
    for _ in range(3):
        store.create()
    store.switch(current)
    store.delete(deleted)
    assert store.count() == 2
    assert store.current == expected


@pytest.mark.parametrize("number", [0, 4, -1, True, "2"])
def test_bad_numbers_are_refused_with_the_valid_range(tmp_path: Path, number: object) -> None:
    store = ActionStore(tmp_path)
    for _ in range(3):
        store.create()
    with pytest.raises(StoreError, match="numbered 1 to 3"):
        store.switch(number)  # type: ignore[arg-type]


def test_unreadable_file_is_a_clear_error(tmp_path: Path) -> None:
    (tmp_path / FILE_NAME).write_text("{not json")
    with pytest.raises(StoreError, match="cannot read the actions file"):
        ActionStore(tmp_path)


def test_atomic_write_leaves_no_temp_files_and_replaces_content(tmp_path: Path) -> None:
    target = tmp_path / "x.json"
    atomic_write_text(target, "old")
    atomic_write_text(target, "new")
    assert target.read_text() == "new"
    assert [p.name for p in tmp_path.iterdir()] == ["x.json"]


def test_killed_writer_leaves_old_or_new_file(tmp_path: Path) -> None:
    """A process killed while saving in a loop never leaves a torn file behind."""
    script = (
        "import sys; from services.executor.store import ActionStore\n"
        "s = ActionStore(sys.argv[1]); s.create()\n"
        "while True:\n"
        "    s.append_step({'procedure': 'open', 'args': {'arm': 'right'}, 'pad': 'x' * 5000})\n"
        "    print('saved', flush=True)\n"
    )
    proc = subprocess.Popen([sys.executable, "-c", script, str(tmp_path)], cwd=ROOT, stdout=subprocess.PIPE, text=True)
    try:
        # the writer says each save it finished: after a few dozen, kill it while it is in the middle of the next
        for _ in range(20):
            assert proc.stdout.readline().strip() == "saved"
        os.kill(proc.pid, signal.SIGKILL)
    finally:
        proc.wait(10)
    data = json.loads((tmp_path / FILE_NAME).read_text())
    assert len(data["actions"][0]["steps"]) >= 20  # every save it reported finished is there
    assert ActionStore(tmp_path).step_counts()[0] == len(data["actions"][0]["steps"])


def test_actions_op_requests(tmp_path: Path) -> None:
    store = ActionStore(tmp_path)
    store.create()
    store.append_step(STEP)
    assert apply_action_op(store, {"op": "rename", "number": 1, "name": " cups "})["name"] == "cups"
    listed = apply_action_op(store, {"op": "list"})
    assert listed["actions"][0]["name"] == "cups" and listed["actions"][0]["steps"] == 1
    with pytest.raises(StoreError, match="unknown actions operation"):
        apply_action_op(store, {"op": "explode"})


def test_command_line_list_show_rename_delete(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    store = ActionStore(tmp_path)
    store.create()
    store.append_step(STEP)
    store.create()
    assert actions_main(["--data-dir", str(tmp_path), "rename", "1", "stack"]) == 0
    assert actions_main(["--data-dir", str(tmp_path), "show", "1"]) == 0
    out = capsys.readouterr().out
    assert "Action 1: stack, 1 steps" in out and "grab the red cup  [red cup]" in out
    assert actions_main(["--data-dir", str(tmp_path), "delete", "2"]) == 0
    assert actions_main(["--data-dir", str(tmp_path), "list"]) == 0
    out = capsys.readouterr().out
    assert "stack" in out and out.count("steps") == 1
    assert actions_main(["show", "7", "--data-dir", str(tmp_path)]) == 1
    assert "there is no action 7" in capsys.readouterr().err


def test_hfpbd_command_reaches_the_actions_tool(tmp_path: Path) -> None:
    ActionStore(tmp_path).create()
    result = subprocess.run(
        [sys.executable, "-m", "hfpbd.cli", "executor", "actions", "list"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        env={**os.environ, "HFPBD_DATA_DIR": str(tmp_path)},
        timeout=60,
    )
    assert result.returncode == 0, result.stderr
    assert "(unnamed)" in result.stdout


def test_undo_removes_the_current_actions_last_step_on_disk(tmp_path: Path) -> None:
    store = ActionStore(tmp_path)
    store.create()
    store.append_step(STEP)
    store.create()
    store.append_step(STEP)
    store.append_step({**STEP, "procedure": "place_abs"})
    assert store.remove_last_step()["procedure"] == "place_abs"
    assert ActionStore(tmp_path).step_counts() == [1, 1]
    store.remove_last_step()
    with pytest.raises(StoreError, match="there is no step to remove"):
        store.remove_last_step()
    assert ActionStore(tmp_path).step_counts() == [1, 0]
