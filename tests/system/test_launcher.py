"""``hfpbd up``: supervision, loopback by default, mutual TLS with roles, one robot per namespace, no orphans."""

from __future__ import annotations

import queue
import signal
import socket
import subprocess
import sys
import time
import uuid
from pathlib import Path

import psutil
import pytest

from hfpbd.launcher import DEFAULT_PORT, hub_listen, local_endpoint
from hfpbd.secure import init
from shared.bus import Bus, BusTimeout
from shared.config import SessionOptions, free_port, loopback_options
from tests.processes import ROOT, start_up
from tests.waiting import eventually


def _run_module(*argv: str, timeout: float = 60) -> subprocess.CompletedProcess[str]:
    """``python -m <argv>`` from the repository root, to its end, its output kept for the assertions."""
    return subprocess.run(
        [sys.executable, "-m", *argv], cwd=ROOT, capture_output=True, text=True, timeout=timeout, check=False
    )


def _wait(predicate, timeout: float) -> bool:
    """Whether ``predicate()`` comes to hold within ``timeout`` seconds (the caller's assertion says what failed)."""
    try:
        eventually(predicate, timeout)
    except AssertionError:
        return False
    return True


@pytest.fixture(autouse=True)
def _private_data_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Every ``hfpbd up`` here keeps its namespace lock (and any actions) under the test's own directory."""
    monkeypatch.setenv("HFPBD_DATA_DIR", str(tmp_path / "data"))


@pytest.fixture
def robot(tmp_path: Path):
    """``hfpbd up --headless`` with the NLU only, on a private port and namespace."""
    namespace, port = "up" + uuid.uuid4().hex[:8], free_port()
    popen = start_up(namespace, port, tmp_path, services=("nlu",))
    bus = Bus(loopback_options(namespace, port, listen=False))
    try:
        yield popen, bus
    finally:
        bus.close()
        if popen.poll() is None:
            popen.kill()
            popen.wait(10)
        for child in psutil.process_iter(["cmdline"]):
            if namespace in " ".join(child.info["cmdline"] or []):
                child.kill()


def test_crashed_service_is_reported_and_restarted_and_stop_leaves_no_orphans(robot) -> None:
    popen, bus = robot
    said: queue.Queue = queue.Queue()
    bus.subscribe(bus.keys.say, said.put, schema="say")
    assert _wait(lambda: "nlu" in bus.alive_services(), 60), "the NLU never came up"
    nlu = psutil.Process(popen.pid).children()[0]
    nlu.kill()
    message = said.get(timeout=20)
    assert message.kind == "error" and "nlu service stopped" in message.text and "restarting" in message.text
    assert _wait(
        lambda: "nlu" in bus.alive_services() and any(c.pid != nlu.pid for c in psutil.Process(popen.pid).children()),
        60,
    )
    children = psutil.Process(popen.pid).children(recursive=True)
    popen.send_signal(signal.SIGINT)
    assert popen.wait(30) == 0
    assert _wait(lambda: not any(c.is_running() and c.status() != psutil.STATUS_ZOMBIE for c in children), 15)


def test_unknown_service_is_refused(tmp_path: Path) -> None:
    result = _run_module("hfpbd.launcher", "--headless", "--services", "nlu,teleporter")
    assert result.returncode != 0 and "unknown service(s) teleporter" in result.stderr


def _listeners(root: psutil.Process) -> list[tuple[str, int]]:
    """Every TCP listening and UDP bound address of ``root`` and its descendants (multicast scouting included)."""
    found = []
    for process in [root, *root.children(recursive=True)]:
        try:
            connections = process.net_connections(kind="inet")
        except psutil.NoSuchProcess:
            continue
        found += [
            (c.laddr.ip, c.laddr.port)
            for c in connections
            if c.status == psutil.CONN_LISTEN or (c.type == socket.SOCK_DGRAM and not c.raddr)
        ]
    return found


def test_robot_and_services_listen_on_loopback_only(robot) -> None:
    popen, bus = robot
    assert _wait(lambda: "nlu" in bus.alive_services(), 60), "the NLU never came up"
    listeners = _listeners(psutil.Process(popen.pid))
    assert len(listeners) >= 2, listeners  # the router and the NLU's own peer listener
    assert all(ip in ("127.0.0.1", "::1") for ip, _ in listeners), listeners


def test_a_second_robot_on_the_namespace_refuses_to_start(robot, tmp_path: Path) -> None:
    popen, bus = robot
    assert _wait(lambda: "nlu" in bus.alive_services(), 60)
    namespace = bus.keys.namespace
    port = int(bus.options.connect[0].rsplit(":", 1)[1])
    children = psutil.Process(popen.pid).children()
    # another data directory: past the namespace lock, the port itself tells
    second = start_up(namespace, port, tmp_path / "second", services=("nlu",), data_dir=tmp_path / "second")
    out, _ = second.communicate(timeout=60)
    assert second.returncode == 1
    assert f"a robot is already up on namespace {namespace!r}" in out and "Traceback" not in out
    assert popen.poll() is None and psutil.Process(popen.pid).children() == children
    assert _wait(lambda: "nlu" in bus.alive_services(), 5)


def test_a_second_robot_on_the_namespace_at_another_port_refuses_to_start(robot, tmp_path: Path) -> None:
    popen, bus = robot
    assert _wait(lambda: "nlu" in bus.alive_services(), 60)
    namespace = bus.keys.namespace
    children = psutil.Process(popen.pid).children()
    second = start_up(namespace, free_port(), tmp_path / "second", services=("nlu",))
    out, _ = second.communicate(timeout=60)
    assert second.returncode == 1, out
    first = f"{bus.options.connect[0]} (process {popen.pid})"
    assert f"a robot is already up on namespace {namespace!r} at {first}; not starting a second one" in out
    assert "Traceback" not in out
    assert popen.poll() is None and psutil.Process(popen.pid).children() == children
    assert _wait(lambda: "nlu" in bus.alive_services(), 5)


def test_a_second_service_on_the_namespace_refuses_to_start(robot) -> None:
    _, bus = robot
    assert _wait(lambda: "nlu" in bus.alive_services(), 60)
    result = _run_module("services.nlu", *bus.options.to_argv(), timeout=90)
    assert result.returncode == 3
    assert f"nlu is already running on namespace {bus.keys.namespace!r}" in result.stderr
    assert "Traceback" not in result.stderr
    assert "nlu" in bus.alive_services()


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGHUP, signal.SIGTERM])
def test_services_end_with_the_launcher_however_it_ends(robot, sig: int) -> None:
    popen, bus = robot
    assert _wait(lambda: "nlu" in bus.alive_services(), 60)
    children = psutil.Process(popen.pid).children(recursive=True)
    assert children
    popen.send_signal(sig)
    popen.wait(30)
    assert _wait(lambda: not any(c.is_running() and c.status() != psutil.STATUS_ZOMBIE for c in children), 20), [
        c.cmdline() for c in children if c.is_running()
    ]


def test_a_listener_beyond_loopback_needs_secure_or_insecure(tmp_path: Path) -> None:
    result = _run_module("hfpbd.launcher", "--headless", "--services", "nlu", "--listen", "tcp/0.0.0.0:7447")
    assert result.returncode == 2
    assert "--secure DIR" in result.stderr and "--insecure" in result.stderr and "Traceback" not in result.stderr


def _secure_up(pki: Path, namespace: str, log_dir: Path, *extra: str) -> subprocess.Popen[str]:
    """``hfpbd up --headless --secure PKI`` with the NLU only, its log lines on its standard output."""
    return subprocess.Popen(
        [
            sys.executable,
            "-m",
            "hfpbd.launcher",
            "--headless",
            "--services",
            "nlu",
            "--namespace",
            namespace,
            "--secure",
            str(pki),
            "--log-dir",
            str(log_dir),
            *extra,
        ],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )


def _remote(namespace: str, port: int, pki: Path, identity: str) -> Bus:
    """A laptop's client session, once the robot listens (a client cannot open before that)."""
    options = SessionOptions(
        namespace=namespace,
        connect=(f"tls/localhost:{port}",),
        multicast_scouting=False,
        secure=str(pki),
        identity=identity,
    )
    eventually(lambda: _port_taken(port), 30, f"the robot listening on port {port}")
    return Bus(options)


def _port_taken(port: int) -> bool:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        return sock.connect_ex(("127.0.0.1", port)) == 0


def test_secure_robot_serves_its_operator_over_mutual_tls(tmp_path: Path) -> None:
    pki = tmp_path / "pki"
    init(pki, host="robot-host")
    namespace, port = "sec" + uuid.uuid4().hex[:8], free_port()
    popen = _secure_up(pki, namespace, tmp_path / "logs", "--listen", f"tls/127.0.0.1:{port}")

    def remote(identity: str) -> Bus:
        return _remote(namespace, port, pki, identity)

    try:
        with remote("operator") as operator:
            assert _wait(lambda: "nlu" in operator.alive_services(), 60), "the NLU never came up"
            reply = operator.request(operator.keys.nlu_query("parse"), {"text": "open your left hand"}, timeout=10)
            assert reply["kind"] == "command" and reply["procedure"] == "open"
            for _ in range(200):  # a forged stream: refused each time, reported once
                operator.publish(operator.keys.objects, {"stamp": 1.0, "objects": []})
            with pytest.raises(BusTimeout):
                operator.request(operator.keys.sim_control("scene"), {"name": "forged"}, timeout=1)
        with remote("observer") as observer, pytest.raises(BusTimeout):
            observer.request(observer.keys.nlu_query("parse"), {"text": "open your left hand"}, timeout=2)
    finally:
        popen.send_signal(signal.SIGINT)
        out, _ = popen.communicate(timeout=30)
    assert popen.returncode == 0, out
    assert out.count(f"refused operator: put on pbd/{namespace}/perception/objects") == 1, out
    assert f"refused operator: query on pbd/{namespace}/sim/control/scene" in out
    assert "is authorized" not in out and "TRACE" not in out  # Zenoh's own trace lines stay out


def test_secure_robot_listens_on_tls_loopback_by_default(tmp_path: Path) -> None:
    """With --secure and no --listen the router enforces the roles, so it must listen on tls/, services included."""
    if _port_taken(DEFAULT_PORT):
        pytest.skip(f"port {DEFAULT_PORT} is in use on this machine")
    pki = tmp_path / "pki"
    init(pki, host="robot-host")
    namespace = "def" + uuid.uuid4().hex[:8]
    popen = _secure_up(pki, namespace, tmp_path / "logs")
    try:
        with _remote(namespace, DEFAULT_PORT, pki, "operator") as operator:
            assert _wait(lambda: "nlu" in operator.alive_services(), 60), "the NLU never came up"
            reply = operator.request(operator.keys.nlu_query("parse"), {"text": "open your left hand"}, timeout=10)
            assert reply["kind"] == "command" and reply["procedure"] == "open"
    finally:
        popen.send_signal(signal.SIGINT)
        out, _ = popen.communicate(timeout=30)
    assert popen.returncode == 0, out
    assert f"router on tls/127.0.0.1:{DEFAULT_PORT};" in out


def test_a_secure_router_in_clear_is_refused(tmp_path: Path) -> None:
    pki = tmp_path / "pki"
    init(pki, host="robot-host")
    result = _run_module("hfpbd.launcher", "--headless", "--secure", str(pki), "--listen", "tcp/127.0.0.1:7447")
    assert result.returncode == 2
    assert "a listener of a session enforcing the roles must be tls/" in result.stderr
    assert "Traceback" not in result.stderr


def test_insecure_listener_warns_and_the_services_stay_on_loopback(tmp_path: Path) -> None:
    namespace, port = "ins" + uuid.uuid4().hex[:8], free_port()
    popen = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "hfpbd.launcher",
            "--headless",
            "--services",
            "nlu",
            "--listen",
            f"tcp/0.0.0.0:{port}",
            "--insecure",
            "--namespace",
            namespace,
            "--log-dir",
            str(tmp_path),
        ],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        with Bus(loopback_options(namespace, port, listen=False)) as bus:
            assert _wait(lambda: "nlu" in bus.alive_services(), 60), "the NLU never came up"
        nlu = psutil.Process(popen.pid).children()[0]
        assert {ip for ip, _ in _listeners(nlu)} <= {"127.0.0.1", "::1"}
        assert ("0.0.0.0", port) in _listeners(psutil.Process(popen.pid))
    finally:
        popen.send_signal(signal.SIGINT)
        out, _ = popen.communicate(timeout=30)
    assert f"--insecure: listening on tcp/0.0.0.0:{port} with no authentication" in out


def test_each_service_killed_mid_run_is_restarted_and_keeps_the_current_action(tmp_path: Path) -> None:
    namespace, port = "kill" + uuid.uuid4().hex[:8], free_port()
    services = ("nlu", "perception", "executor")
    popen = start_up(namespace, port, tmp_path / "logs", services=services, data_dir=tmp_path / "data")
    bus = Bus(loopback_options(namespace, port, listen=False))
    said: queue.Queue = queue.Queue()
    bus.subscribe(bus.keys.say, said.put, schema="say")
    actions = bus.keys.executor_control("actions")
    try:
        assert _wait(lambda: set(services) <= bus.alive_services(), 90), bus.alive_services()
        reply = bus.request(bus.keys.executor_control("command"), {"procedure": "create_action", "args": {}})
        assert reply["ok"], reply
        assert _wait(lambda: bus.request(actions, {"op": "list"})["current"] == 1, 10)
        for name in services:
            child = next(c for c in psutil.Process(popen.pid).children() if f"services.{name}" in c.cmdline())
            child.kill()
            deadline = time.monotonic() + 20
            text = ""
            while f"{name} service stopped" not in text and time.monotonic() < deadline:
                text = said.get(timeout=max(0.1, deadline - time.monotonic())).text
            assert f"The {name} service stopped" in text and "restarting it" in text
            assert _wait(
                lambda name=name, old=child.pid: (
                    name in bus.alive_services() and old not in [c.pid for c in psutil.Process(popen.pid).children()]
                ),
                60,
            ), f"{name} did not come back"
        assert _wait(lambda: set(services) <= bus.alive_services(), 30)
        listed = bus.request(actions, {"op": "list"}, timeout=10)
        assert listed["current"] == 1 and len(listed["actions"]) == 1, listed
        assert (
            bus.request(bus.keys.nlu_query("parse"), {"text": "open your left hand"}, timeout=10)["kind"] == "command"
        )
        assert (tmp_path / "data" / namespace / "actions.json").is_file()
    finally:
        bus.close()
        popen.send_signal(signal.SIGINT)
        popen.communicate(timeout=60)


@pytest.mark.parametrize(
    "listen, router, services",
    [
        ("tcp/127.0.0.1:7447", ("tcp/127.0.0.1:7447",), "tcp/127.0.0.1:7447"),
        ("tls/0.0.0.0:7447", ("tls/0.0.0.0:7447",), "tls/127.0.0.1:7447"),
        ("tls/[::]:7448", ("tls/[::]:7448",), "tls/127.0.0.1:7448"),
        ("tls/192.168.1.20:7447", ("tls/192.168.1.20:7447", "tls/127.0.0.1:7447"), "tls/127.0.0.1:7447"),
    ],
)
def test_the_services_reach_the_router_on_loopback(listen: str, router: tuple[str, ...], services: str) -> None:
    assert hub_listen(listen) == router
    assert local_endpoint(listen) == services
