"""The loop's timing helpers: when to read a frame being rendered, and when a stopped arm has come to rest."""

from __future__ import annotations

import numpy as np
import pytest

from services.sim.halt import AT_REST, WATCH_FOR, Halting
from services.sim.render_time import LONGEST, SHORTEST, SHRINK, RenderWait
from services.sim.scene_file import load_scene
from services.sim.world import SimWorld


def test_the_render_wait_converges_on_the_renderers_time_from_above() -> None:
    renderer = 0.045  # s the renderer takes per frame
    wait = RenderWait(initial=0.01)
    read_times = []
    for _ in range(60):
        read_took = max(renderer - wait.wait, 0.0005)  # a read early by x waits x; a late one is instant
        read_times.append(read_took)
        wait.learn(read_took)
    assert SHRINK * renderer - 0.001 <= wait.wait <= renderer + 0.001
    assert max(read_times[-30:]) <= (1 - SHRINK) * renderer + 0.001  # the loop never waits long on a frame


def test_the_render_wait_stays_within_its_bounds() -> None:
    wait = RenderWait()
    for _ in range(200):
        wait.learn(0.0)
    assert wait.wait == SHORTEST
    wait.learn(10.0)
    assert wait.wait == LONGEST
    assert wait.ready(taken_at=1.0, now=1.0 + LONGEST) and not wait.ready(taken_at=1.0, now=1.0)


def test_halting_fires_once_when_every_stopped_joint_is_at_rest() -> None:
    halting = Halting()
    assert not halting.watching
    halting.stopped([1, 3], sim_time=0.0)
    moving = np.array([0.0, 0.5, 0.0, 0.01])
    assert not halting.came_to_rest(moving, 0.004)
    at_rest = np.array([0.9, AT_REST / 2, 0.0, -AT_REST / 2])  # joint 0 was not stopped: it may move
    assert halting.came_to_rest(at_rest, 0.008)
    assert not halting.watching


def test_halting_gives_up_on_a_joint_that_never_rests() -> None:
    halting = Halting()
    halting.stopped([0], sim_time=1.0)
    assert not halting.came_to_rest(np.array([1.0]), 1.0 + WATCH_FOR / 2)
    assert halting.came_to_rest(np.array([1.0]), 1.0 + WATCH_FOR)


@pytest.fixture(scope="module")
def small_world() -> SimWorld:
    world = SimWorld(width=160, height=120)
    world.load(load_scene("default"))
    return world


def test_a_picture_is_read_as_the_world_was_when_it_was_taken(small_world: SimWorld) -> None:
    picture = small_world.take_picture()
    taken_at = small_world.sim_time
    for _ in range(10):
        small_world.step()
    frame = small_world.read_picture(picture)
    assert frame is not None and frame.sim_time == taken_at
    assert np.isfinite(frame.position).all() and frame.position.shape == (120, 160, 4)


def test_a_picture_taken_before_a_reload_is_dropped(small_world: SimWorld) -> None:
    picture = small_world.take_picture()
    small_world.load(load_scene("default"))
    assert small_world.read_picture(picture) is None
    assert small_world.capture().scene_generation == small_world.scene_generation
