"""The push-to-talk key against a real speech service, and what the user is told when there is none."""

from __future__ import annotations

import asyncio
import queue
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from services.speech import espeak
from services.speech.audio import silence
from shared.bus import Bus
from shared.messages import PttReply
from tests.processes import Launcher, Network
from tests.speech.helpers import stream
from tests.tui.helpers import until
from tests.waiting import served
from tui.app import NO_SPEECH, PbdApp
from tui.conversation import Conversation
from tui.status_bar import StatusBar

pytestmark = pytest.mark.asyncio

SIZE = (120, 40)


def status(app: PbdApp) -> StatusBar:
    return app.query_one(StatusBar)


@pytest.mark.skipif(not espeak.available(), reason="espeak-ng is not installed")
async def test_the_talk_key_lets_the_speech_service_hear_a_command(network: Network, launcher: Launcher) -> None:
    hub = network.hub
    heard: queue.Queue[dict[str, Any]] = queue.Queue()
    hub.subscribe(hub.keys.utterance, heard.put)
    launcher.start("speech", "--trigger", "ptt", "--microphone", "off", "--no-voice")
    said = np.concatenate([silence(0.3), espeak.synthesise("look at the red cup", "en-us", 150), silence(0.3)])
    app = PbdApp(network.client_options, probe_seconds=None)
    async with app.run_test(size=SIZE) as pilot:
        await until(pilot, lambda: "speech" in status(app).alive, timeout=30, what="the speech service")
        await pilot.press("f9")
        await until(pilot, lambda: status(app).talking, what="listening")
        assert "listening…" in status(app).summary()
        stream(hub, said)
        await pilot.press("f9")
        await until(pilot, lambda: not status(app).talking, what="done listening")
        assert "listening" not in status(app).summary()
        await until(pilot, lambda: not heard.empty(), timeout=60, what="the utterance")
        utterance = heard.get()
        assert (utterance["text"], utterance["source"]) == ("look at the red cup", "speech")
        assert not conversation_lines(app, "warning") and not conversation_lines(app, "error")


def conversation_lines(app: PbdApp, kind: str) -> list[str]:
    return app.query_one(Conversation).texts(kind)


def no_speech(hub: Bus) -> None:
    """Nothing: the speech service is not running."""


def silent_speech(hub: Bus) -> None:
    """A speech token whose push-to-talk queryable never answers (a hung service)."""
    hub.declare_alive("speech")


def refusing_speech(hub: Bus) -> None:
    """A speech service that refuses push-to-talk with its reason."""
    hub.declare_alive("speech")

    def refuse(_request: dict[str, Any]) -> PttReply:
        raise ValueError("the microphone is busy")

    hub.serve(hub.keys.speech("ptt"), refuse)


@pytest.mark.parametrize(
    "setup, kind, told",
    [
        (no_speech, "warning", NO_SPEECH),
        (silent_speech, "error", "push-to-talk failed: the speech service did not answer (is it running?)"),
        (refusing_speech, "error", "push-to-talk failed: the microphone is busy"),
    ],
    ids=["not-running", "not-answering", "refusing"],
)
async def test_the_talk_key_without_a_working_speech_service_says_why(
    network: Network, setup: Callable[[Bus], None], kind: str, told: str
) -> None:
    setup(network.hub)
    app = PbdApp(network.client_options, probe_seconds=None)
    async with app.run_test(size=SIZE) as pilot:
        await until(pilot, lambda: app.bridge.connected, what="the UI's session")
        if setup is not no_speech:
            await until(pilot, lambda: "speech" in status(app).alive, what="the speech token")
        if setup is refusing_speech:  # the UI's session must know the queryable before it asks
            assert app.bridge.bus is not None
            await asyncio.to_thread(served, app.bridge.bus, network.hub.keys.speech("ptt"))
        await pilot.press("f9")
        await until(pilot, lambda: conversation_lines(app, kind), timeout=10, what=f"the {kind} line")
        assert conversation_lines(app, kind) == [told]
        assert not status(app).talking and "listening" not in status(app).summary()
