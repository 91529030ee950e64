"""A moving arm over the real simulated table never becomes an object.

The scene is built in-process with the simulator's own library. A cloud
arrives after it was rendered, when the newest state already shows the arm
further on; perception masks the arm at the states on both sides of the
cloud's time, as the service does.
"""

from __future__ import annotations

import numpy as np
import pytest

from services.perception.evaluate import score
from services.perception.pipeline import detect

sim_world = pytest.importorskip("services.sim.world", reason="the simulator library is not available")
from services.sim.cloud import cloud_message  # noqa: E402
from services.sim.scene_file import load_scene  # noqa: E402
from shared.messages import SimState, as_received  # noqa: E402
from shared.robot import ROBOT  # noqa: E402

OVER_THE_TABLE = np.array([-0.6, 0.6, 0.0, -1.0, 0.0, -0.9, 0.0])
ACROSS = np.array([0.3, 0.5, 0.0, -0.8, 0.0, -1.0, 0.0])
FRAMES = 7
DELAY = 0.1  # s of simulated time between rendering a cloud and the newest state


def sim_state(world) -> SimState:
    """The world's ``sim/state`` as perception's subscription hands it over."""
    state = as_received("sim_state", {"stamp": 0.0, **world.state()})
    assert isinstance(state, SimState)
    return state


@pytest.fixture(scope="module")
def sweep() -> list[tuple]:
    """(cloud, state at render time, state DELAY later, truth) while the right arm sweeps across."""
    world = sim_world.SimWorld()
    world.load(load_scene("refexp_4_mixed"))
    world.settle(0.3)
    names = ROBOT.arm_joint_names("right")
    world.move_joints("right_arm", names, OVER_THE_TABLE, "m1")
    world.settle(3.0)
    world.move_joints("right_arm", names, ACROSS, "m2")
    frames = []
    for _ in range(FRAMES):
        world.settle(0.1)
        before = sim_state(world)
        message = as_received("cloud", cloud_message(world.capture(), world.sim_time))
        world.settle(DELAY)
        frames.append((message, before, sim_state(world), world.truth()))
    return frames


@pytest.mark.parametrize("frame", range(FRAMES))
def test_no_phantom_from_the_arm_with_the_states_around_the_cloud(sweep, frame):
    message, before, after, truth = sweep[frame]
    result = score(detect(message, after, earlier=before).objects, truth)
    assert result.phantoms == 0
    assert result.found >= len(truth) - 1  # the arm may hide one object at a time, never show a false one


def test_the_arm_really_crossed_the_table(sweep):
    tool_y = [frame[1].ee["right"][1] for frame in sweep]
    assert max(tool_y) - min(tool_y) > 0.3
