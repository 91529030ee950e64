"""The UI's bridge to the bus: news it posts can always be acted on at once."""

from __future__ import annotations

import threading
from typing import Any

from textual.message import Message

from tests.tui.helpers import DESCRIPTIONS, fixed_network, stage_world
from tui import events
from tui.bridge import Bridge


class Answering:
    """Stands in for the app: on objects seen or a service appearing, it asks the NLU at once, as the app does."""

    def __init__(self) -> None:
        self.bridge: Bridge | None = None
        self.answers: dict[str, Any] = {}
        self.done = threading.Event()

    def post_message(self, message: Message) -> bool:
        news = "objects" if isinstance(message, events.ObjectsSeen) else None
        if isinstance(message, events.Presence) and message.service == "nlu":
            news = "nlu"
        if news is not None:
            assert self.bridge is not None
            try:
                self.answers[news] = self.bridge.describe()
            except ConnectionError as exc:
                self.answers[news] = exc
        if len(self.answers) == 2:
            self.done.set()
        return True


def test_news_from_a_subscriptions_history_finds_the_bus_ready_to_ask() -> None:
    """The objects' cached sample and the services' presence arrive while the subscriptions are being
    declared; a request made from their handlers right then must reach the NLU, not "not connected"."""
    with fixed_network("bridgeready") as (hub, options):
        world = stage_world(hub)
        app = Answering()
        bridge = app.bridge = Bridge(options, app)
        try:
            bridge.open()
            assert app.done.wait(10.0), f"only {sorted(app.answers)} came"
            assert app.answers == {"objects": DESCRIPTIONS, "nlu": DESCRIPTIONS}
        finally:
            bridge.close()
        del world
