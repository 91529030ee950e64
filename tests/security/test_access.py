"""Real TLS sessions on loopback against a robot host's router: who gets in, and what each identity may do."""

from __future__ import annotations

import json
import queue

import pytest
import zenoh

from shared.bus import BusTimeout
from shared.config import SessionOptions, zenoh_config
from tests.security.conftest import RobotHost, collect
from tests.waiting import eventually, subscribed

UTTERANCE = {"text": "move your right hand up"}
AUDIO = {"stamp": 1.0, "rate": 16000, "pcm": b"\x00\x00" * 160}
# the operator's other queryables (beside nlu/**), each answered by a robot-side stand-in
COMMAND_QUERIES = ("executor/control/command", "sim/control/stop", "speech/ptt")


def _serve_parse(host: RobotHost) -> None:
    host.service.serve(host.key("nlu/parse"), lambda request: {"ok": True, "heard": request.get("text")})


def _serve_commands(host: RobotHost) -> None:
    """Robot-side queryables on :data:`COMMAND_QUERIES` that answer with the key they serve."""
    for key in COMMAND_QUERIES:
        host.service.serve(host.key(key), lambda request, key=key: {"ok": True, "served": key})


def _reaches_service(host: RobotHost, key: str, send) -> bool:
    """Whether ``send()`` (a remote put) gets a message to the robot-side service within a few seconds."""
    received = collect(host.service, host.key(key))
    subscribed(host.router, host.key(key))

    def delivered() -> bool:
        send()
        try:
            received.get(timeout=0.3)
        except queue.Empty:
            return False
        return True

    try:
        return eventually(delivered, 3, f"a message on {key} at the service")
    except AssertionError:
        return False


def _bad_client(host: RobotHost, change) -> zenoh.Config:
    """A client config to the router, then altered by ``change(config)``."""
    config = zenoh_config(
        SessionOptions(
            namespace=host.namespace,
            mode="client",
            connect=(host.endpoint,),
            multicast_scouting=False,
            secure=str(host.pki),
            identity="operator",
        )
    )
    change(config)
    return config


def _plain_tcp(config: zenoh.Config, host: RobotHost) -> None:
    config.insert_json5("connect/endpoints", json.dumps([f"tcp/127.0.0.1:{host.port}"]))


def _no_certificate(config: zenoh.Config, _host: RobotHost) -> None:
    for name in ("connect_certificate", "connect_private_key", "listen_certificate", "listen_private_key"):
        config.insert_json5(f"transport/link/tls/{name}", "null")
    config.insert_json5("transport/link/tls/enable_mtls", "false")  # TLS that trusts the robot but shows nothing


@pytest.mark.parametrize("how", ["plain-tcp", "tls-without-certificate", "certificate-from-another-ca"])
def test_unauthenticated_clients_get_nothing(robot_host: RobotHost, foreign_pki, how: str) -> None:
    def foreign(config: zenoh.Config, _host: RobotHost) -> None:  # trusts our CA, presents another's certificate
        for side in ("connect", "listen"):
            config.insert_json5(f"transport/link/tls/{side}_certificate", json.dumps(str(foreign_pki / "operator.pem")))
            config.insert_json5(
                f"transport/link/tls/{side}_private_key", json.dumps(str(foreign_pki / "operator-key.pem"))
            )

    change = {
        "plain-tcp": _plain_tcp,
        "tls-without-certificate": _no_certificate,
        "certificate-from-another-ca": foreign,
    }[how]
    # refused by the robot's listener at the handshake: a client session cannot even open
    with pytest.raises(zenoh.ZError, match="Unable to connect"):
        zenoh.open(_bad_client(robot_host, lambda config: change(config, robot_host)))


def test_operator_commands_and_receives(robot_host: RobotHost) -> None:
    _serve_parse(robot_host)
    _serve_commands(robot_host)
    robot_host.service.declare_alive("nlu")
    cached = robot_host.service.publisher(robot_host.key("executor/state"), cached=True)
    cached.put({"stamp": 1.0, "robot": {"action": 3}})
    with robot_host.remote("operator") as operator:
        assert _reaches_service(
            robot_host, "dialog/utterance", lambda: operator.publish(operator.keys.utterance, UTTERANCE)
        )
        assert _reaches_service(
            robot_host, "speech/audio", lambda: operator.publish(robot_host.key("speech/audio"), AUDIO)
        )
        assert operator.request(operator.keys.nlu_query("parse"), {"text": "hello"}, timeout=5)["heard"] == "hello"
        for key in COMMAND_QUERIES:
            assert operator.request(robot_host.key(key), {}, timeout=5)["served"] == key
        history = collect(operator, operator.keys.executor_state, history=True)
        assert history.get(timeout=5)["robot"]["action"] == 3, "a cached stream's last sample reaches the operator"
        said = collect(operator, operator.keys.say)
        subscribed(robot_host.service, robot_host.service.keys.say)
        robot_host.service.publish(robot_host.service.keys.say, {"text": "done", "kind": "info"})
        assert said.get(timeout=5)["text"] == "done"
        eventually(lambda: "nlu" in operator.alive_services(), 5, "the nlu's token at the operator")


def test_observer_receives_but_cannot_command(robot_host: RobotHost) -> None:
    _serve_parse(robot_host)
    _serve_commands(robot_host)
    with robot_host.remote("observer") as observer:
        assert not _reaches_service(
            robot_host, "dialog/utterance", lambda: observer.publish(observer.keys.utterance, UTTERANCE)
        )
        assert not _reaches_service(
            robot_host, "speech/audio", lambda: observer.publish(robot_host.key("speech/audio"), AUDIO)
        )
        for key in ("nlu/parse", *COMMAND_QUERIES):
            with pytest.raises(BusTimeout):
                observer.request(robot_host.key(key), {"text": "hello"}, timeout=1)
        said = collect(observer, observer.keys.say)
        subscribed(robot_host.service, robot_host.service.keys.say)
        robot_host.service.publish(robot_host.service.keys.say, {"text": "seen", "kind": "info"})
        assert said.get(timeout=5)["text"] == "seen"


@pytest.mark.parametrize("key", ["perception/objects", "sim/control/scene", "executor/state"])
def test_operator_cannot_forge_what_the_robot_trusts(robot_host: RobotHost, key: str) -> None:
    answered: list = []
    robot_host.service.serve(robot_host.key("sim/control/scene"), lambda request: answered.append(request) or {})
    with robot_host.remote("operator") as operator:
        forged = {"stamp": 1.0, "objects": [], "robot": {}, "name": "forged"}
        assert not _reaches_service(robot_host, key, lambda: operator.publish(robot_host.key(key), forged))
        with pytest.raises(BusTimeout):
            operator.request(operator.keys.sim_control("scene"), {"name": "forged"}, timeout=1)
    assert not answered


def test_an_operator_never_becomes_a_peer(pki) -> None:
    options = SessionOptions(namespace="x", connect=("tls/localhost:1",), secure=str(pki), identity="operator")
    assert json.loads(zenoh_config(options).get_json("mode")) == "client"
    assert json.loads(zenoh_config(options).get_json("listen/endpoints")) == []
