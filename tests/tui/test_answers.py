"""Answers to questions in the conversation: their own style, shown once, and spoken by the voice.

The NLU and the speech service run as their own processes; the test's hub
publishes the objects as perception would and a narration as the executor
would, so the lines compared are the ones the services really caused.
"""

from __future__ import annotations

import queue
import time
from pathlib import Path
from typing import Any

import pytest
from rich.style import Style

from tests.processes import Launcher, Network
from tests.tui.helpers import OBJECTS, until
from tui.app import PbdApp
from tui.conversation import Conversation
from tui.status_bar import StatusBar

pytestmark = pytest.mark.asyncio


def _style_of(conversation: Conversation, text: str) -> Style | None:
    """The style the log drew ``text`` in (the words after the speaker's prefix)."""
    for strip in conversation.lines:
        for segment in strip:
            if segment.text.startswith(text[:15]):
                return segment.style
    return None


def _spoken(folder: Path) -> list[Path]:
    return sorted(folder.glob("say-*.wav"))


async def test_an_answer_is_shown_once_in_its_own_style_and_spoken(
    network: Network, launcher: Launcher, tmp_path: Path
) -> None:
    hub = network.hub
    hub.publisher(hub.keys.objects, cached=True).put({"stamp": time.time(), "objects": OBJECTS})
    results: queue.Queue[dict[str, Any]] = queue.Queue()
    hub.subscribe(hub.keys.nlu_result, results.put)
    voice = tmp_path / "voice"
    launcher.start("nlu")
    launcher.start("speech", "--microphone", "off", "--voice-dir", str(voice))
    app = PbdApp(network.client_options, probe_seconds=None)
    async with app.run_test(size=(120, 40)) as pilot:
        conversation = app.query_one(Conversation)
        await until(pilot, lambda: bool(app.world.descriptions), timeout=30, what="the NLU's referring expressions")
        await until(pilot, lambda: "speech" in app.query_one(StatusBar).alive, timeout=60, what="the speech service")
        hub.publish(hub.keys.say, {"text": "Moving my right hand up.", "kind": "narration"})
        await until(pilot, lambda: "Moving my right hand up." in conversation.texts("narration"), what="narration")
        await until(pilot, lambda: len(_spoken(voice)) == 1, timeout=20, what="the narration spoken")

        await pilot.press(*"where is the red cup", "enter")
        await until(pilot, lambda: bool(conversation.texts("answer")), timeout=20, what="the answer")
        answer = conversation.texts("answer")[0]
        result = results.get(timeout=5)
        assert result["kind"] == "answer" and result["topic"] == "object" and answer == result["text"]
        assert "cm in front of me" in answer and "cup" in answer
        await until(pilot, lambda: len(_spoken(voice)) == 2, timeout=20, what="the answer spoken")
        await pilot.pause(0.5)
        assert answer not in conversation.texts("info"), "the answer was shown a second time as information"
        assert _style_of(conversation, answer) not in (None, _style_of(conversation, "Moving my right hand up."))
