"""The actions screen (F4) against the executor's real actions queryable code and a real store on disk."""

from __future__ import annotations

import os
import time
from collections.abc import AsyncIterator, Iterator
from contextlib import asynccontextmanager
from pathlib import Path

import pytest
from textual.pilot import Pilot

from services.executor.store import ActionStore
from tests.tui.helpers import TAUGHT, fixed_network, hub_bridge, serve_actions, stage_world, teach, until
from tests.tui.test_snapshots import settled
from tui.actions_screen import ActionsScreen, created_text
from tui.app import PbdApp


@pytest.fixture
def utc() -> Iterator[None]:
    """Creation times read the same on every machine."""
    before = os.environ.get("TZ")
    os.environ["TZ"] = "UTC"
    time.tzset()
    yield
    if before is None:
        os.environ.pop("TZ")
    else:
        os.environ["TZ"] = before
    time.tzset()


@asynccontextmanager
async def actions_screen(
    tmp_path: Path, name: str, size: tuple[int, int] = (100, 30), serve: bool = True
) -> AsyncIterator[tuple[PbdApp, Pilot, ActionStore, list]]:
    """The app with the actions screen open over a store holding ``TAUGHT``."""
    store = ActionStore(tmp_path)
    teach(store)
    runs: list[tuple[int, int]] = []
    with fixed_network(name) as (hub, options):
        world = stage_world(hub)
        if serve:
            serve_actions(hub, store, runs)
        app = PbdApp(options, probe_seconds=None, camera_drawing="halfcell", bridge=hub_bridge(hub))
        async with app.run_test(size=size) as pilot:
            await settled(app, hub)(pilot)
            await pilot.press("f4")
            await until(pilot, lambda: isinstance(app.screen, ActionsScreen), what="the actions screen")
            if serve:
                await until(pilot, lambda: len(app.screen.actions) == len(TAUGHT), what="the list")
            yield app, pilot, store, runs
        del world


def note(app: PbdApp) -> str:
    return str(app.screen.query_one("#actions-note").render())


@pytest.mark.asyncio
async def test_every_action_is_listed_with_its_steps_in_the_users_words(tmp_path: Path, utc: None) -> None:
    async with actions_screen(tmp_path, "actlist") as (app, pilot, _store, _runs):
        table = app.screen.query_one("#actions-table")
        rows = [[str(cell) for cell in table.get_row_at(i)] for i in range(table.row_count)]
        assert [row[1:4] for row in rows] == [
            ["1", "stack the cups", "4"],
            ["2", "(unnamed)", "3"],
            ["3", "tidy the box", "1"],
        ]
        assert rows[0][4] == "2025-12-01 12:00" and rows[0][0] == "▶"
        await pilot.press("down")
        steps = app.screen.query_one("#steps-table")
        assert [str(steps.get_row_at(i)[1]) for i in range(steps.row_count)] == TAUGHT[1][2]
        await pilot.press("f4")
        await until(pilot, lambda: not isinstance(app.screen, ActionsScreen), what="the screen to close")


@pytest.mark.asyncio
async def test_rename_is_saved_in_the_store(tmp_path: Path) -> None:
    async with actions_screen(tmp_path, "actrename") as (app, pilot, store, _runs):
        await pilot.press("down", "r")
        await pilot.press(*"lift the plate", "enter")
        await until(pilot, lambda: store.get(2)["name"] == "lift the plate", what="the new name")
        await until(pilot, lambda: app.screen.actions[1].name == "lift the plate", what="the list again")
        assert "renamed action 2" in note(app)


@pytest.mark.asyncio
async def test_a_name_taken_or_meaning_a_command_is_refused_with_the_reason(tmp_path: Path) -> None:
    async with actions_screen(tmp_path, "actrenameno") as (app, pilot, store, _runs):
        await pilot.press("down", "r", *"Stack the cups", "enter")
        await until(pilot, lambda: "rename failed" in note(app), what="the refusal")
        assert "Action 1 is already called \u201cstack the cups\u201d" in note(app)
        await pilot.press("r", *"pick up", "enter")
        await until(pilot, lambda: "one of my commands" in note(app), what="the second refusal")
        assert store.get(2)["name"] is None


@pytest.mark.asyncio
async def test_delete_needs_the_key_twice(tmp_path: Path) -> None:
    async with actions_screen(tmp_path, "actdelete") as (app, pilot, store, _runs):
        await pilot.press("d")
        assert "press d again to delete action 1" in note(app) and store.count() == 3
        await pilot.press("down", "d", "up")  # another key in between keeps it
        await pilot.press("d")
        assert store.count() == 3
        await pilot.press("d")
        await until(pilot, lambda: store.count() == 2, what="the delete")
        assert [a["name"] for a in store.summaries()] == [None, "tidy the box"]


@pytest.mark.asyncio
async def test_a_step_is_deleted_and_another_moved(tmp_path: Path) -> None:
    async with actions_screen(tmp_path, "actsteps") as (app, pilot, store, _runs):
        said = TAUGHT[0][2]
        await pilot.press("tab", "down", "x", "x")
        await until(pilot, lambda: len(store.get(1)["steps"]) == 3, what="the step delete")
        assert [s["utterance"] for s in store.get(1)["steps"]] == [said[0], said[2], said[3]]
        await until(pilot, lambda: app.screen.actions[0].steps == 3, what="the list again")
        await pilot.press("down", "down", "[")
        await until(pilot, lambda: store.get(1)["steps"][1]["utterance"] == said[3], what="the move")
        assert [s["utterance"] for s in store.get(1)["steps"]] == [said[0], said[3], said[2]]
        await pilot.press("up", "up", "[")
        assert "step 1 is already the first" in note(app)


@pytest.mark.asyncio
async def test_execute_starts_from_the_highlighted_step(tmp_path: Path) -> None:
    async with actions_screen(tmp_path, "actexec") as (app, pilot, _store, runs):
        await pilot.press("tab", "down", "down", "e")
        await until(pilot, lambda: runs == [(1, 3)], what="the run")
        await until(pilot, lambda: "executing action 1 from step 3" in note(app), what="the note")


@pytest.mark.asyncio
async def test_without_an_executor_the_screen_says_so(tmp_path: Path) -> None:
    async with actions_screen(tmp_path, "actnoexec", serve=False) as (app, pilot, _store, _runs):
        await until(pilot, lambda: "did not answer" in note(app), what="the reason")
        assert "list failed: the executor did not answer (is it running?)" in note(app)


@pytest.mark.unit
def test_creation_time_reads_as_local_date_and_minute(utc: None) -> None:
    assert created_text(1764590400.0) == "2025-12-01 12:00"
    assert created_text(None) == "—"
