"""Each namespace keeps its own actions, and two executors never write one file."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from services.executor.store import FILE_NAME, ActionStore, StoreError, hold_store, namespace_dir
from tests.processes import ROOT

HOLDER = ("import sys; from pathlib import Path; from services.executor.store import hold_store; "
          "h = hold_store(Path(sys.argv[1])); print('held', flush=True); sys.stdin.read()")


def test_each_namespace_has_its_own_store(tmp_path: Path) -> None:
    ActionStore(namespace_dir(tmp_path, "robot1")).create("stack")
    assert ActionStore(namespace_dir(tmp_path, "robot2")).count() == 0
    assert (tmp_path / "robot1" / FILE_NAME).is_file() and not (tmp_path / "robot2" / FILE_NAME).exists()


def test_the_default_namespace_takes_over_the_old_top_level_store(tmp_path: Path) -> None:
    ActionStore(tmp_path).create("from before")
    store = ActionStore(namespace_dir(tmp_path, "default"))
    assert store.summaries()[0]["name"] == "from before"
    assert not (tmp_path / FILE_NAME).exists(), "one file only, not two copies"
    assert ActionStore(namespace_dir(tmp_path, "other")).count() == 0


def test_a_second_executor_on_one_store_is_refused_while_the_first_lives(tmp_path: Path) -> None:
    holder = subprocess.Popen([sys.executable, "-c", HOLDER, str(tmp_path)], cwd=ROOT, stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        with pytest.raises(StoreError, match=f"another executor \\(process {holder.pid}\\)"):
            hold_store(tmp_path)
    finally:
        holder.kill()
        holder.wait(10)
    hold_store(tmp_path).close()  # the lock went with the process, even killed
