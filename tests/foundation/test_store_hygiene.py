"""Each namespace keeps its own actions, and two executors never write one file."""

from __future__ import annotations

import random
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from services.executor.store import (
    FILE_NAME,
    ActionStore,
    StoreError,
    hold_store,
    namespace_dir,
)
from shared.bus import Bus
from shared.config import free_port, loopback_options
from shared.service import ALREADY_RUNNING
from tests.processes import ROOT, Launcher, Network
from tests.waiting import eventually

HOLDER = (
    "import sys; from pathlib import Path; from services.executor.store import hold_store; "
    "h = hold_store(Path(sys.argv[1])); print('held', flush=True); sys.stdin.read()"
)


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
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLDER, str(tmp_path)],
        cwd=ROOT,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout.readline().strip() == "held"
        with pytest.raises(StoreError, match=f"another executor \\(process {holder.pid}\\)"):
            hold_store(tmp_path)
    finally:
        holder.kill()
        holder.wait(10)
    hold_store(tmp_path).close()  # the lock went with the process, even killed


def test_a_second_executor_on_a_held_store_exits_as_already_running(
    network: Network, launcher: Launcher, tmp_path: Path
) -> None:
    """One namespace and data directory, each executor on its own router: no token tells them apart, the lock does."""
    data = tmp_path / "data"
    first = launcher.start("executor", "--data-dir", str(data))
    port = free_port()
    with Bus(loopback_options(network.namespace, port, listen=True)):
        second = subprocess.run(
            [
                sys.executable,
                "-m",
                "services.executor",
                *loopback_options(network.namespace, port, listen=False).to_argv(),
                "--data-dir",
                str(data),
            ],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=90,
            check=False,
        )
    assert second.returncode == ALREADY_RUNNING, second.stderr
    assert (
        f"executor is already running on namespace {network.namespace!r}: another executor "
        f"(process {first.popen.pid}) is using the actions in {data / network.namespace}; not starting a second one"
    ) in second.stderr
    assert "Traceback" not in second.stderr
    assert first.exited() is None


WRITER = (
    "import sys; from services.executor.store import ActionStore; s = ActionStore(sys.argv[1]); "
    "s.create('kept')\nprint('ready', flush=True)\nwhile True: s.append_step({'procedure': 'open', "
    "'args': {'arm': 'right'}, 'words': 'open your right hand ' * 50})"
)


def test_the_actions_file_survives_sigkill_during_writes(tmp_path: Path) -> None:
    """A loop of kills at random moments of a writing process: the file always loads, nothing is lost.

    Each kill comes once a random number of further steps is on disk: the
    writer is then somewhere in its next write, wherever the scheduler has it.
    """
    rng = random.Random(3)
    steps = 0
    for kill in range(12):
        writer = subprocess.Popen(
            [sys.executable, "-c", WRITER, str(tmp_path)], cwd=ROOT, stdout=subprocess.PIPE, text=True
        )
        assert writer.stdout.readline().strip() == "ready"
        on_disk, target = ActionStore(tmp_path), steps + rng.randint(0, 30)
        eventually(lambda store=on_disk, n=target: sum(store.step_counts()) >= n, 30, f"{target} steps written")
        writer.send_signal(signal.SIGKILL)
        writer.wait(10)
        store = ActionStore(tmp_path)  # raises StoreError on a torn file
        counts = store.step_counts()
        assert [a["name"] for a in store.summaries()] == ["kept"] * (kill + 1), "an action saved earlier was lost"
        assert sum(counts) >= steps, "steps saved earlier were lost"
        steps = sum(counts)
    assert steps > 0
