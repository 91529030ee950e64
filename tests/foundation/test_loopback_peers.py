"""Peers listening on loopback only still find each other through the one they all connect to."""

from __future__ import annotations

import queue
import uuid

from shared.bus import Bus
from shared.config import SessionOptions, free_port
from tests.waiting import subscribed


def test_peers_of_a_listening_peer_reach_each_other_on_loopback() -> None:
    namespace, port = "p" + uuid.uuid4().hex[:8], free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    listening = Bus(SessionOptions(namespace=namespace, listen=(endpoint,), multicast_scouting=False))
    first = Bus(SessionOptions(namespace=namespace, connect=(endpoint,), multicast_scouting=False))
    second = Bus(SessionOptions(namespace=namespace, connect=(endpoint,), multicast_scouting=False))
    try:
        received: queue.Queue = queue.Queue()
        second.subscribe(second.keys.utterance, received.put, schema="utterance")
        subscribed(first, first.keys.utterance)
        first.publish(first.keys.utterance, {"text": "hello"})
        message = received.get(timeout=10)
        assert message is not None and message.text == "hello"
        assert second.session.info.zid() in list(first.session.info.peers_zid()), "the two peers connected directly"
    finally:
        for bus in (second, first, listening):
            bus.close()
