"""The in-progress marker: what a restarted executor knows about the command its predecessor died in."""

from __future__ import annotations

from pathlib import Path

import pytest

from services.executor.interrupted import MARKER_NAME, InProgress, interrupted_sentence

pytestmark = pytest.mark.unit


def test_a_command_that_ended_leaves_nothing_to_report(tmp_path: Path) -> None:
    marker = InProgress(tmp_path)
    marker.begin("picking up the red cup with your right hand")
    marker.end()
    assert InProgress(tmp_path).take() is None


def test_a_command_cut_short_is_reported_once(tmp_path: Path) -> None:
    InProgress(tmp_path).begin("picking up the red cup with your right hand")
    restarted = InProgress(tmp_path)
    assert restarted.take() == "picking up the red cup with your right hand"
    assert restarted.take() is None and not (tmp_path / MARKER_NAME).exists()


def test_an_unreadable_marker_still_says_a_command_was_cut_short(tmp_path: Path) -> None:
    (tmp_path / MARKER_NAME).write_text('{"doing": ')
    assert InProgress(tmp_path).take() == "a command"


def test_the_sentence_names_what_was_cut_short_and_what_is_kept() -> None:
    text = interrupted_sentence("picking up the red cup with your right hand", 2, 1)
    assert text == (
        "I was interrupted while picking up the red cup with your right hand: I had to restart, "
        "so it was not finished. Action 2 still has 1 step. Tell me what to do next."
    )
    assert "Action" not in interrupted_sentence("creating an action", 0, 0)
