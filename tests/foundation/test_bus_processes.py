"""The bus across real processes: pub/sub, queries, presence, bad input, big clouds."""

from __future__ import annotations

import hashlib
import queue
import signal
import time

import numpy as np
import pytest

from shared.bus import BusTimeout, RemoteError
from tests.processes import Launcher, Network
from tests.waiting import eventually, subscribed


@pytest.fixture
def echo(launcher: Launcher):
    return launcher.start("echo", module="tests.echo_peer")


def _collect(network: Network, suffix: str) -> queue.Queue:
    """What the echo peer publishes on ``suffix`` from now on.

    A request answered after the subscription is declared is the round trip
    that proves the peer knows it: declarations travel ahead of queries.
    """
    received: queue.Queue = queue.Queue()
    network.hub.subscribe(f"pbd/{network.namespace}/{suffix}", received.put)
    network.hub.request(f"pbd/{network.namespace}/test/echo", {"text": "ready"})
    return received


def test_publish_crosses_to_another_process_and_back(network: Network, echo) -> None:
    received = _collect(network, "test/out")
    subscribed(network.hub, f"pbd/{network.namespace}/test/in")
    network.hub.publish(f"pbd/{network.namespace}/test/in", {"text": "hello"})
    message = received.get(timeout=10)
    assert message is not None and message["text"] == "hello"


def test_query_gets_reply(network: Network, echo) -> None:
    reply = network.hub.request(f"pbd/{network.namespace}/test/echo", {"text": "ping"}, timeout=5)
    assert reply == {"v": 1, "ok": True, "echo": "ping"}


def test_query_without_queryable_times_out_cleanly(network: Network, echo) -> None:
    started = time.monotonic()
    with pytest.raises(BusTimeout, match="no reply"):
        network.hub.request(f"pbd/{network.namespace}/test/nobody", {}, timeout=0.5)
    assert time.monotonic() - started < 3


def test_failing_handler_becomes_error_reply(network: Network, echo) -> None:
    with pytest.raises(RemoteError, match="division by zero"):
        network.hub.request(f"pbd/{network.namespace}/test/fail", {}, timeout=5)
    # the service is still serving afterwards
    assert network.hub.request(f"pbd/{network.namespace}/test/echo", {"text": "x"})["echo"] == "x"


@pytest.mark.parametrize(
    "payload",
    [b"", b"\xc1garbage", b"\x92\x01\x02", b"\x81\xa1v\x63", b"\x82\xa1v\x01\xa4text\x05"],
    ids=["empty", "not-msgpack", "not-a-map", "wrong-version", "wrong-field-type"],
)
def test_malformed_payload_is_counted_not_fatal(network: Network, echo, payload: bytes) -> None:
    received = _collect(network, "test/out")
    subscribed(network.hub, f"pbd/{network.namespace}/test/in")
    network.hub.session.put(f"pbd/{network.namespace}/test/in", payload)
    rejected = eventually(
        lambda: network.hub.request(f"pbd/{network.namespace}/test/stats", {})["rejected"], 10, "the rejection counted"
    )
    assert rejected == 1
    network.hub.publish(f"pbd/{network.namespace}/test/in", {"text": "still alive"})
    assert received.get(timeout=5)["text"] == "still alive"
    assert echo.popen.poll() is None


def test_liveliness_appears_and_vanishes_when_killed(network: Network, launcher: Launcher, echo) -> None:
    assert "echo" in network.hub.alive_services()
    echo.kill(signal.SIGKILL)
    assert launcher.wait_alive("echo", alive=False, timeout=15)


def test_sigterm_exits_promptly_and_cleanly(launcher: Launcher, echo) -> None:
    started = time.monotonic()
    code = echo.stop(grace=10)
    assert code == 0, echo.log()
    assert time.monotonic() - started < 10
    assert "stopped" in echo.log()


def test_a_burst_of_signals_ends_the_service_cleanly(echo) -> None:
    """Signals arriving while the last one is handled (a parent dying as the launcher stops it) end it once."""
    for index in range(200):
        echo.kill(signal.SIGTERM if index % 2 else signal.SIGINT)
    eventually(lambda: echo.exited() is not None, 15, "the echo peer to exit")
    assert echo.exited() == 0, echo.log_tail()
    assert echo.log().count("echo stopped") == 1


def test_point_cloud_sized_message_crosses_intact(network: Network, echo) -> None:
    rng = np.random.default_rng(7)
    xyz = rng.normal(size=(480, 640, 3)).astype(np.float32)
    rgb = rng.integers(0, 256, size=(480, 640, 3), dtype=np.uint8)
    digest = hashlib.sha256(xyz.tobytes() + rgb.tobytes()).hexdigest()
    received = _collect(network, "test/out")
    publisher = network.hub.publisher(network.hub.keys.cloud, large=True)
    subscribed(network.hub, network.hub.keys.cloud)
    publisher.put(
        {"stamp": 1.0, "xyz": xyz, "rgb": rgb, "camera_pose": [0, 0, 1, 1, 0, 0, 0], "width": 640, "height": 480}
    )
    reply = received.get(timeout=15)
    assert xyz.nbytes + rgb.nbytes == 4_608_000
    assert reply["digest"] == digest and reply["shape"] == [480, 640, 3]
