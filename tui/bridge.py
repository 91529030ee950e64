"""The bus side of the terminal UI.

Zenoh delivers samples on the bus's worker threads; every handler here only
turns the sample into a Textual message and posts it (thread-safe, never
blocks), so a slow screen never stalls the bus and a closed app never raises
on a Zenoh thread. Requests block, so the app calls them from
``@work(thread=True)`` workers, never from its event loop.
"""

from __future__ import annotations

import time
from typing import Any, Protocol

from textual.message import Message

from shared.bus import Bus, BusTimeout, RemoteError
from shared.config import SessionOptions
from shared.messages import (
    ACTIONS_REPLIES,
    Cloud,
    CommandReply,
    Descriptions,
    ExecutorState,
    NluResult,
    Objects,
    PttReply,
    Reply,
    Say,
    SimState,
    SnapshotReply,
    SpeechPtt,
    Utterance,
    Vocabulary,
)
from tui import events

# A cheap, side-effect-free request per service, timed for the status bar.
# Services without one in the contract show presence only.
PROBES: dict[str, tuple[str, dict[str, Any]]] = {
    "nlu": ("nlu/vocabulary", {}),
    "executor": ("executor/control/actions", {"op": "list"}),
}


class Poster(Protocol):
    def post_message(self, message: Message) -> bool: ...


class Bridge:
    """Owns the app's Zenoh session: subscriptions in, utterances and requests out."""

    def __init__(self, options: SessionOptions, app: Poster) -> None:
        self.options = options
        self._app = app
        self.bus: Bus | None = None
        self._camera = False

    @property
    def connected(self) -> bool:
        return self.bus is not None

    def open(self) -> None:
        """Open the session and declare every subscription (blocking: call from a worker).

        The bus is usable before the first subscription is declared: a
        subscription's history arrives at once, and a handler of it (asking the
        NLU to describe the objects just seen) must find the bus there.
        """
        bus = self.bus = Bus(self.options)
        keys = bus.keys
        bus.subscribe(keys.say, self._on_say, schema="say")
        bus.subscribe(keys.utterance, self._on_utterance, schema="utterance")
        bus.subscribe(keys.nlu_result, self._on_nlu_result, schema="nlu_result")
        bus.subscribe(keys.objects, self._on_objects, schema="objects", latest_only=True, history=True)
        bus.subscribe(
            keys.executor_state, self._on_executor_state, schema="executor_state", latest_only=True, history=True
        )
        bus.subscribe(keys.sim_state, self._on_sim_state, schema="sim_state", latest_only=True)
        bus.watch_alive(self._on_presence)
        self._app.post_message(events.BusConnected())

    def _on_presence(self, service: str, alive: bool) -> None:
        self._app.post_message(events.Presence(service, alive))

    def watch_camera(self) -> None:
        """Start receiving the head camera (first time it is shown only: frames are megabytes each)."""
        bus = self._bus()
        if not self._camera:
            self._camera = True
            bus.subscribe(bus.keys.cloud, self._on_cloud, schema="cloud", latest_only=True)

    def close(self) -> None:
        if self.bus is not None:
            bus, self.bus = self.bus, None
            bus.close()

    # -- incoming ------------------------------------------------------------
    def _on_say(self, msg: Say) -> None:
        self._app.post_message(events.Said(msg.text, msg.kind, list(msg.candidates or []), msg.topic))

    def _on_utterance(self, msg: Utterance) -> None:
        """What the speech service heard, shown as heard (typed lines are already on screen as the user's)."""
        if msg.source != "speech":
            return
        best = (msg.nbest or [{}])[0].get("score")
        sure = float(best) if isinstance(best, (int, float)) and not isinstance(best, bool) and 0 < best <= 1 else None
        self._app.post_message(events.Heard(msg.text, sure))

    def _on_nlu_result(self, msg: NluResult) -> None:
        self._app.post_message(events.Understood(msg))

    def _on_objects(self, msg: Objects) -> None:
        self._app.post_message(events.ObjectsSeen(msg.objects, msg.status))

    def _on_executor_state(self, msg: ExecutorState) -> None:
        self._app.post_message(events.ExecutorChanged(msg.robot, msg.reach))

    def _on_sim_state(self, msg: SimState) -> None:
        self._app.post_message(events.SimMoved(msg.ee, msg.grippers, msg.moving))

    def _on_cloud(self, msg: Cloud) -> None:
        self._app.post_message(events.CloudSeen(msg))

    # -- outgoing ------------------------------------------------------------
    def _bus(self) -> Bus:
        if self.bus is None:
            raise ConnectionError("not connected to the robot's network yet")
        return self.bus

    def say(self, text: str, choice: int | None = None) -> None:
        """Publish an utterance; ``choice`` answers the pending clarification by index."""
        bus = self._bus()
        bus.publish(bus.keys.utterance, Utterance(text=text, source="tui", choice=choice))

    def command(self, procedure: str, args: dict[str, Any] | None = None, timeout: float = 3.0) -> str:
        """Ask the executor to run a direct command; returns its message."""
        bus = self._bus()
        reply = bus.request(
            bus.keys.executor_control("command"),
            {"procedure": procedure, "args": args or {}},
            reply=CommandReply,
            timeout=timeout,
        )
        return reply.message

    def stop(self) -> str:
        """Stop the robot: through the executor, or straight at the simulator when it is gone.

        Stopping must work even when the executor has died mid-motion, so a
        missing executor falls back to the simulator's own stop.
        """
        try:
            return self.command("stop", timeout=1.0) or "stopped"
        except BusTimeout:
            bus = self._bus()
            bus.request(bus.keys.sim_control("stop"), {}, timeout=2.0)
            return "stopped the arms directly (the executor did not answer)"

    def talk(self, on: bool) -> bool:
        """Press (``on``) or release push-to-talk on the speech service; returns whether it now listens."""
        bus = self._bus()
        return bus.request(bus.keys.speech("ptt"), SpeechPtt(on=on), reply=PttReply, timeout=2.0).listening

    def actions(self, request: dict[str, Any]) -> Reply:
        """One request on the executor's actions queryable (list, rename, delete, steps, execute), read as its op's reply."""
        bus = self._bus()
        kind = ACTIONS_REPLIES.get(request["op"], Reply)
        return bus.request(bus.keys.executor_control("actions"), request, reply=kind, timeout=3.0)

    def snapshot(self) -> bytes:
        """A PNG of the whole robot from the simulator's overview camera (rendering takes a moment)."""
        bus = self._bus()
        return bus.request(bus.keys.sim_control("snapshot"), {}, reply=SnapshotReply, timeout=20.0).png

    def describe(self) -> dict[str, str]:
        bus = self._bus()
        return bus.request(bus.keys.nlu_query("describe"), {}, reply=Descriptions, timeout=3.0).by_id

    def vocabulary(self) -> tuple[list[str], list[str]]:
        bus = self._bus()
        reply = bus.request(bus.keys.nlu_query("vocabulary"), {}, reply=Vocabulary, timeout=3.0)
        return reply.words, reply.phrases

    def ping(self, service: str) -> float | None:
        """Round-trip seconds of the service's probe request, None if it did not answer."""
        if service not in PROBES:
            return None
        bus = self._bus()
        suffix, request = PROBES[service]
        start = time.perf_counter()
        try:
            bus.request(f"pbd/{bus.keys.namespace}/{suffix}", request, timeout=2.0)
        except BusTimeout:
            return None
        except RemoteError:
            pass  # an error reply still measures the round trip
        return time.perf_counter() - start
