"""The executor and perception need nothing of the simulator but its messages: they run with it unimportable.

A real simulator runs in its own process; perception and the executor run in
processes where ``services.sim`` cannot be imported at all (a
``sitecustomize`` guard on their path), as they would on a robot where no
simulator code is installed. They must see the table and the objects, map
what can be reached, pick a cup up (judged held from the gripper's opening
and effort alone) and put it down — each outcome judged from the
simulator's ground truth.
"""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from services.sim.layout import TABLE_TOP_Z, TABLE_X
from tests.executor.stack import Stack, texts
from tests.processes import ROOT

GUARD = "import sys\nsys.modules['services.sim'] = None   # no simulator code on this machine\n"
ROBOT_SIDE = ("services/executor", "services/perception")


def sim_imports(path: Path) -> list[str]:
    """The ``services.sim`` imports in one module, written as ``file:line``."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):  # "from services import sim" names it too
            names = [f"{node.module}.{alias.name}" for alias in node.names]
        else:
            continue
        if any(name == "services.sim" or name.startswith("services.sim.") for name in names):
            found.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    return found


@pytest.mark.unit
def test_no_robot_side_module_imports_the_simulator() -> None:
    modules = [p for folder in ROBOT_SIDE for p in sorted((ROOT / folder).rglob("*.py"))]
    assert len(modules) > 20
    assert [hit for module in modules for hit in sim_imports(module)] == []


@pytest.fixture(scope="module")
def guard(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """The environment of a process that cannot import the simulator (checked to really be so)."""
    folder = tmp_path_factory.mktemp("no_sim")
    (folder / "sitecustomize.py").write_text(GUARD)
    env = {"PYTHONPATH": os.pathsep.join([str(folder), str(ROOT)])}
    probe = subprocess.run(
        [sys.executable, "-c", "import services.sim.layout"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        env={**os.environ, **env},
        timeout=60,
    )
    assert probe.returncode != 0 and "services.sim" in probe.stderr, probe.stderr
    return env


@pytest.fixture(scope="module")
def stack(tmp_path_factory: pytest.TempPathFactory, guard: dict[str, str]) -> Iterator[Stack]:
    running = Stack(tmp_path_factory.mktemp("logs"), tmp_path_factory.mktemp("data"))
    try:
        running.launcher.start("sim")
        running.launcher.start("perception", env=guard)
        running.executor = running.launcher.start("executor", "--data-dir", str(running.data_dir), env=guard)
        running.wait_for(lambda: running.state is not None and running.state["reach"], 90, "a first reach map")
        running.load_scene("default")
        yield running
    finally:
        running.close()


def test_perception_measures_the_table_and_its_near_edge(stack: Stack) -> None:
    reply = stack.hub.request(stack.hub.keys.record, {}, timeout=30)
    table = reply["table"]
    assert table["height"] == pytest.approx(TABLE_TOP_Z, abs=0.005)
    assert table["edges"]["near"] == pytest.approx(TABLE_X[0], abs=0.005)
    assert table["extent"]["x"][0] == pytest.approx(TABLE_X[0], abs=0.005)
    assert len(reply["objects"]) == len(stack.truth)


def test_the_executor_maps_reach_for_every_object(stack: Stack) -> None:
    reach = stack.state["reach"]
    assert set(reach) == {o["id"] for o in stack.objects.values() if o.get("visible", True)}
    assert reach[stack.pid("obj0")]["right"]["pick_up"]


def test_a_cup_is_picked_up_held_and_put_back_on_the_table(stack: Stack) -> None:
    before = stack.position("obj0")
    said = stack.command("pick_up", {"arm": "right", "object": stack.pid("obj0")})
    assert texts(said, "error") == []
    lifted = stack.position("obj0")
    assert lifted[2] > before[2] + 0.08, "the cup was not lifted"
    assert np.linalg.norm(lifted[:2] - stack.ee("right")[:2]) < 0.08, "the cup did not move with the hand"
    gripper = stack.robot["grippers"]["right"]
    assert gripper["width"] > 0.05 and gripper["effort"] > 20.0, gripper
    assert stack.state["robot"]["grippers"]["right"] == "holding"
    assert stack.state["robot"]["holding"]["right"] == stack.pid("obj0")

    said = stack.command("place_abs", {"arm": "right", "destination": "table"})
    assert texts(said, "error") == []
    down = stack.position("obj0")
    assert down[2] == pytest.approx(before[2], abs=0.01), "the cup is not standing on the table"
    assert stack.state["robot"]["grippers"]["right"] == "open"
