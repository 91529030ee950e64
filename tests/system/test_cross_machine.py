"""Services "on separate machines": the simulator only listens, everything else connects to it by address.

No session here goes through a test hub or finds another by multicast: the
simulator's session listens on one TCP endpoint and connects nowhere;
perception, NLU, executor and this test's own session connect to that
endpoint explicitly with multicast scouting off — what a robot host and a
workstation would be given on the command line.
"""

from __future__ import annotations

import uuid
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from hfpbd.tasks.runner import TaskRunner
from hfpbd.tasks.scripts import Expected, Utterance
from hfpbd.tasks.stack import LocalStack
from shared.bus import Bus
from shared.config import SessionOptions, free_port


@pytest.fixture
def split(tmp_path: Path) -> Iterator[tuple[TaskRunner, LocalStack]]:
    namespace, port = "x" + uuid.uuid4().hex[:10], free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    robot_host = SessionOptions(namespace=namespace, listen=(endpoint,), multicast_scouting=False)
    workstation = SessionOptions(namespace=namespace, connect=(endpoint,), multicast_scouting=False)
    assert "--connect" not in robot_host.to_argv()
    watcher = Bus(workstation)  # keeps retrying its endpoint until the simulator listens there
    stack = LocalStack(watcher, tmp_path)
    try:
        stack.start("sim", robot_host.to_argv())
        for name in ("perception", "nlu"):
            stack.start(name, workstation.to_argv())
        stack.start("executor", workstation.to_argv(), "--data-dir", str(tmp_path / "data"))
        yield TaskRunner(watcher), stack
    finally:
        stack.stop()
        watcher.close()


@pytest.mark.slow
def test_objects_flow_and_a_spoken_command_moves_the_arm(split: tuple[TaskRunner, LocalStack]) -> None:
    runner, _ = split
    runner.wait_for_services()
    truth = runner.load_scene("default")
    red = np.asarray(truth["obj0"].position)
    assert {o.color for o in runner.watch.objects.values()} >= {"red", "blue"}, "perception saw nothing through the sim"

    step = runner.say(
        Utterance(
            "Move your right hand above the red cup.",
            Expected("move_rel_dest", {"arm": "right", "relation": "above", "object": "obj0"}),
        )
    )
    assert step.ok, step.problem
    assert runner.watch.sim is not None
    tool = np.asarray(runner.watch.sim.ee["right"])
    assert np.linalg.norm(tool[:2] - red[:2]) < 0.04, "the right hand is not over the red cup"
    assert tool[2] > red[2] + 0.08
