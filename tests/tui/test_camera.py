"""The head camera in the UI: the camera model from the frame, outlines and names where objects are, F2, F3."""

from __future__ import annotations

import io
import threading
from typing import Any

import msgspec
import numpy as np
import pytest
from PIL import Image
from textual_image import widget as image_widgets

from shared.messages import Cloud, PerceivedObject, SimState, SnapshotReply, typed
from tests.tui.camera_frame import FOCAL, HEIGHT, WIDTH, frame
from tests.tui.helpers import DESCRIPTIONS, OBJECTS, SIM_STATE, fixed_network, hub_bridge, stage_world, until
from tests.tui.test_snapshots import settled
from tui import main as tui_main
from tui.app import PbdApp
from tui.camera import compose, fit_cells, fit_pinhole
from tui.camera_view import DRAWINGS, CameraView, image_class
from tui.conversation import Conversation
from tui.overview_screen import OverviewScreen
from tui.world import WorldView
from tui.world_panel import WorldPanel

CELL = (10, 20)
HALF_BLOCKS = (1, 2)


def _world(objects: list[dict[str, Any]] = OBJECTS, **changes: object) -> WorldView:
    """The UI's world as the bridge fills it from the bus: ``objects`` and the robot as typed messages."""
    state = typed("sim_state", {"stamp": 1.0, **SIM_STATE})
    assert isinstance(state, SimState)
    world = WorldView(
        objects={o["id"]: msgspec.convert(o, PerceivedObject) for o in objects},
        descriptions=dict(DESCRIPTIONS),
        ee=state.ee,
        grippers=state.grippers,
    )
    for name, value in changes.items():
        setattr(world, name, value)
    return world


def _cloud(message: dict[str, Any]) -> Cloud:
    """A ``sim/cloud`` frame as the bridge hands it to the camera view."""
    cloud = typed("cloud", message)
    assert isinstance(cloud, Cloud)
    return cloud


@pytest.mark.unit
def test_the_camera_model_is_recovered_from_the_frame_itself() -> None:
    camera = fit_pinhole(frame()["xyz"], frame()["camera_pose"])
    assert camera is not None
    assert camera.fx == pytest.approx(FOCAL, rel=1e-3) and camera.fy == pytest.approx(FOCAL, rel=1e-3)
    assert (camera.cx, camera.cy) == pytest.approx((WIDTH / 2, HEIGHT / 2), abs=0.05)


@pytest.mark.unit
def test_each_object_projects_onto_its_own_colour() -> None:
    cloud = frame()
    camera = fit_pinhole(cloud["xyz"], cloud["camera_pose"])
    uv, ahead = camera.project(np.array([o["position"] for o in OBJECTS]))
    assert ahead.all()
    for obj, (u, v) in zip(OBJECTS, uv, strict=True):
        assert list(cloud["rgb"][int(v), int(u)]) == obj["rgb"], obj["id"]


@pytest.mark.unit
def test_objects_are_named_by_their_referring_expressions_never_by_id() -> None:
    picture = compose(_cloud(frame()), _world(highlighted="obj0"), 60, 20, CELL, HALF_BLOCKS)
    names = [label.text for label in picture.labels]
    assert sorted(names) == sorted([*DESCRIPTIONS.values(), "L", "R"])
    assert not any(name.startswith("obj") for name in names)
    assert "ffd700" in next(label.style for label in picture.labels if label.text == "the red cup")


@pytest.mark.unit
def test_an_object_not_yet_described_reads_by_colour_and_type() -> None:
    picture = compose(_cloud(frame()), _world(descriptions={}), 60, 20, CELL, HALF_BLOCKS)
    assert "a red cup" in [label.text for label in picture.labels]


@pytest.mark.unit
def test_the_outline_surrounds_the_object_in_the_scaled_picture() -> None:
    picture = compose(_cloud(frame()), _world(highlighted="obj0"), 60, 20, CELL, HALF_BLOCKS)
    pixels = np.asarray(picture.image)
    camera = fit_pinhole(frame()["xyz"], frame()["camera_pose"])
    ((u, v),) = camera.project(np.array([OBJECTS[0]["position"]]))[0] * [
        picture.image.width / WIDTH,
        picture.image.height / HEIGHT,
    ]
    row = pixels[int(v)]
    left = [c for c in range(int(u)) if tuple(row[c]) == (255, 215, 0)]
    right = [c for c in range(int(u) + 1, len(row)) if tuple(row[c]) == (255, 215, 0)]
    assert left and right, "no highlight outline on both sides of the red cup"


@pytest.mark.unit
def test_labels_of_objects_side_by_side_do_not_cover_each_other() -> None:
    cups = [{**OBJECTS[0], "id": f"obj{i}", "position": [0.62, -0.15 + 0.08 * i, 0.80]} for i in range(3)]
    world = _world(
        objects=cups,
        descriptions={"obj0": "the rightmost cup", "obj1": "the middle cup", "obj2": "the leftmost cup"},
    )
    labels = compose(_cloud(frame(cups)), world, 60, 20, CELL, HALF_BLOCKS).labels
    for i, one in enumerate(labels):
        for other in labels[i + 1 :]:
            apart = one.column + len(one.text) <= other.column or other.column + len(other.text) <= one.column
            assert one.row != other.row or apart, f"{one.text!r} covers {other.text!r}"


@pytest.mark.unit
def test_the_close_up_shows_the_objects_larger() -> None:
    cup = {**OBJECTS[0], "position": [0.62, 0.0, 0.80]}
    world = _world(objects=[cup])

    def red_pixels(close_up: bool) -> int:
        picture = compose(_cloud(frame([cup])), world, 60, 20, CELL, HALF_BLOCKS, close_up=close_up)
        assert abs(picture.columns - 53) <= 1 and picture.rows == 20  # the same space, the frame's shape kept
        pixels = np.asarray(picture.image).astype(int)
        return int((np.abs(pixels - cup["rgb"]).sum(axis=-1) < 60).sum())

    assert red_pixels(True) >= 4 * red_pixels(False) > 0


@pytest.mark.unit
def test_grippers_are_marked_where_the_tool_frames_are() -> None:
    picture = compose(_cloud(frame()), _world(), 60, 20, CELL, HALF_BLOCKS)
    marks = {label.text: label.column for label in picture.labels if label.text in ("L", "R")}
    assert marks["L"] < picture.columns / 2 < marks["R"], "the robot's left hand must show on the picture's left"


@pytest.mark.unit
def test_a_frame_without_points_is_shown_without_marks() -> None:
    cloud = frame()
    cloud["xyz"] = np.full_like(cloud["xyz"], np.nan)
    picture = compose(_cloud(cloud), _world(), 60, 20, CELL, HALF_BLOCKS)
    assert picture.labels == [] and picture.image.size == (picture.columns, 2 * picture.rows)


@pytest.mark.unit
@pytest.mark.parametrize("space, expected", [((60, 20), (53, 20)), ((30, 40), (30, 11)), ((200, 5), (13, 5))])
def test_the_picture_keeps_its_shape_in_any_space(space: tuple[int, int], expected: tuple[int, int]) -> None:
    assert fit_cells(WIDTH, HEIGHT, *space, CELL) == expected


@pytest.mark.unit
def test_the_command_line_offers_every_drawing_method() -> None:
    assert set(tui_main.DRAWINGS) == set(DRAWINGS)


@pytest.mark.unit
def test_off_a_terminal_auto_draws_in_colour() -> None:
    assert image_class("auto") is image_widgets.HalfcellImage  # the tests' output is no terminal
    assert image_class("sixel") is image_widgets.SixelImage


@pytest.mark.asyncio
async def test_f2_shows_the_camera_and_every_key_typed_arrives_while_pictures_come() -> None:
    with fixed_network("campilot") as (hub, options):
        world = stage_world(hub)
        app = PbdApp(options, probe_seconds=None, camera_drawing="halfcell", bridge=hub_bridge(hub))
        async with app.run_test(size=(120, 40)) as pilot:
            await settled(app, hub)(pilot)
            view, entry = app.main.query_one(CameraView), app.main.query_one("#input")
            typed = "move your right hand above the red cup"

            async def type_it() -> None:
                entry.value = ""
                await pilot.press(*typed)
                assert entry.value == typed

            await type_it()
            assert not view.display
            await pilot.press("f2")
            assert view.display and not app.main.query_one("#canvas").display
            streaming = threading.Event()
            cloud = frame()

            def camera() -> None:  # the simulator's rate: 5 frames a second
                while not streaming.wait(0.2):
                    hub.publish(hub.keys.cloud, cloud)

            thread = threading.Thread(target=camera, daemon=True)
            thread.start()
            try:
                await until(pilot, lambda: len(view.shown) >= 2, what="camera pictures")
                await type_it()  # every key arrives while pictures come in
                count = len(view.shown)
                await until(pilot, lambda: len(view.shown) >= count + 5, what="five more pictures")
            finally:
                streaming.set()
                thread.join(timeout=5)
            assert sorted(label.text for label in view.picture.labels) == sorted([*DESCRIPTIONS.values(), "L", "R"])
            await pilot.press("f2")
            assert view.display and app.main.query_one(WorldPanel).close_up
            await pilot.press("f2")
            assert not view.display and app.main.query_one("#canvas").display
        del world


def _png(width: int = 80, height: int = 60) -> bytes:
    buffer = io.BytesIO()
    Image.new("RGB", (width, height), (30, 120, 200)).save(buffer, format="png")
    return buffer.getvalue()


@pytest.mark.asyncio
async def test_f3_shows_the_simulators_overview_picture() -> None:
    with fixed_network("camoverview") as (hub, options):
        world = stage_world(hub)
        asked: list[dict] = []
        hub.serve(
            hub.keys.sim_control("snapshot"),
            lambda request: (asked.append(request), SnapshotReply(ok=True, png=_png()))[1],
        )
        app = PbdApp(options, probe_seconds=None, camera_drawing="halfcell", bridge=hub_bridge(hub))
        async with app.run_test(size=(100, 30)) as pilot:
            await settled(app, hub)(pilot)
            await pilot.press("f3")
            await until(pilot, lambda: isinstance(app.screen, OverviewScreen), what="the overview")
            assert asked and app.screen.picture.size == (80, 60)
            await pilot.press("f3")
            await until(pilot, lambda: not isinstance(app.screen, OverviewScreen), what="the overview to close")
        del world


@pytest.mark.asyncio
async def test_f3_without_a_simulator_says_why() -> None:
    with fixed_network("camnosim") as (hub, options):
        world = stage_world(hub)
        app = PbdApp(options, probe_seconds=None, camera_drawing="halfcell", bridge=hub_bridge(hub))
        async with app.run_test(size=(100, 30)) as pilot:
            await settled(app, hub)(pilot)
            await pilot.press("f3")
            conversation = app.main.query_one(Conversation)
            await until(
                pilot,
                lambda: any("overview picture failed" in text for text in conversation.texts("error")),
                what="the reason",
            )
            assert any("the simulator did not answer" in text for text in conversation.texts("error"))
        del world


@pytest.mark.asyncio
async def test_a_frame_that_cannot_be_drawn_is_said_and_the_next_one_shows() -> None:
    with fixed_network("cambad") as (hub, options):
        world = stage_world(hub)
        app = PbdApp(options, probe_seconds=None, camera_drawing="halfcell", bridge=hub_bridge(hub))
        async with app.run_test(size=(120, 40)) as pilot:
            await settled(app, hub)(pilot)
            await pilot.press("f2")
            view = app.main.query_one(CameraView)
            waiting = app.main.query_one("#camera-waiting")
            bad = {**frame(), "rgb": np.zeros((HEIGHT, WIDTH), np.uint8)}  # grey, where colour is expected
            hub.publish(hub.keys.cloud, bad)  # the hub knows the camera's subscription once F2 is handled
            await until(pilot, lambda: "could not be drawn" in str(waiting.render()), what="the bad frame said")
            assert "could not be drawn" in str(waiting.render()) and app.is_running
            hub.publish(hub.keys.cloud, frame())
            await until(pilot, lambda: view.picture is not None, what="the next frame")
            assert view.picture is not None and not waiting.display
        del world
