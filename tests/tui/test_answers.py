"""Answers to questions in the conversation: their own style, shown once, and spoken by the voice.

An answer travels twice: on ``nlu/result`` and, marked with its topic, on
``dialog/say``. The two arrive in either order, so the first test hands them
to the app one after the other in both orders (each one taken in by the app
before the next is published); the second runs the NLU and the speech
service as their own processes, so the lines compared are the ones the
services really caused.
"""

from __future__ import annotations

import queue
import time
from pathlib import Path
from typing import Any

import pytest
from rich.style import Style
from textual.message import Message

from tests.processes import Launcher, Network
from tests.tui.helpers import OBJECTS, connected, hub_bridge, until
from tui import events
from tui.app import PbdApp
from tui.conversation import Conversation
from tui.status_bar import StatusBar

pytestmark = pytest.mark.asyncio

ANSWER = "The red cup is 62 cm in front of me, 15 cm to my right."
RESULT = {"kind": "answer", "topic": "object", "utterance": "where is the red cup", "text": ANSWER}
SPOKEN = {"text": ANSWER, "kind": "info", "topic": "object"}


def _style_of(conversation: Conversation, text: str) -> Style | None:
    """The style the log drew ``text`` in (the words after the speaker's prefix)."""
    for strip in conversation.lines:
        for segment in strip:
            if segment.text.startswith(text[:15]):
                return segment.style
    return None


def _spoken(folder: Path) -> list[Path]:
    return sorted(folder.glob("say-*.wav"))


def _carries_answer(message: Message) -> bool:
    """Whether the app took in one of the answer's two messages."""
    if isinstance(message, events.Understood):
        return message.result.text == ANSWER
    return isinstance(message, events.Said) and message.text == ANSWER


@pytest.mark.parametrize("spoken_first", [False, True], ids=["result-first", "spoken-copy-first"])
async def test_an_answer_is_one_line_in_its_own_style_whichever_copy_comes_first(
    network: Network, spoken_first: bool
) -> None:
    hub = network.hub
    copies = [(hub.keys.nlu_result, RESULT), (hub.keys.say, SPOKEN)]
    taken_in: list[Message] = []

    def hook(message: Message) -> None:
        if _carries_answer(message):
            taken_in.append(message)

    app = PbdApp(network.client_options, probe_seconds=None, bridge=hub_bridge(hub))
    async with app.run_test(size=(120, 40), message_hook=hook) as pilot:
        conversation = app.query_one(Conversation)
        await connected(pilot, app)
        hub.publish(hub.keys.say, {"text": "There is nothing to stop.", "kind": "info"})
        hub.publish(hub.keys.say, {"text": "I can't reach the plate with my right hand.", "kind": "error"})
        await until(pilot, lambda: len(conversation.entries) == 2, what="an information and an error line")

        for count, (key, message) in enumerate(reversed(copies) if spoken_first else copies, start=1):
            hub.publish(key, message)
            await until(pilot, lambda n=count: len(taken_in) == n, what=f"copy {count} of the answer taken in")
        await pilot.pause()

        assert conversation.texts().count(ANSWER) == 1, conversation.entries
        assert conversation.texts("answer") == [ANSWER]
        style = _style_of(conversation, ANSWER)
        others = {_style_of(conversation, "There is nothing to stop."), _style_of(conversation, "I can't reach")}
        assert style is not None and None not in others and style not in others


async def test_a_typed_question_is_answered_once_in_its_own_style_and_spoken(
    network: Network, launcher: Launcher, tmp_path: Path
) -> None:
    hub = network.hub
    hub.publisher(hub.keys.objects, cached=True).put({"stamp": time.time(), "objects": OBJECTS})
    results: queue.Queue[dict[str, Any]] = queue.Queue()
    hub.subscribe(hub.keys.nlu_result, results.put)
    voice = tmp_path / "voice"
    launcher.start("nlu")
    launcher.start("speech", "--microphone", "off", "--voice-dir", str(voice))
    taken_in: list[str] = []

    def hook(message: Message) -> None:
        if isinstance(message, events.Understood) and message.result.text:
            taken_in.append(message.result.text)
        elif isinstance(message, events.Said):
            taken_in.append(message.text)

    app = PbdApp(network.client_options, probe_seconds=None)
    async with app.run_test(size=(120, 40), message_hook=hook) as pilot:
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
        await until(pilot, lambda: taken_in.count(answer) == 2, what="both copies of the answer taken in")
        await pilot.pause()
        assert conversation.texts().count(answer) == 1, "the answer was shown more than once"
        assert _style_of(conversation, answer) not in (None, _style_of(conversation, "Moving my right hand up."))
