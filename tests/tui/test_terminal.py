"""The real ``hfpbd tui`` program in a real terminal (tmux), used as a person would: talking, the camera, actions."""

from __future__ import annotations

import queue
import shutil
import subprocess
import sys
import threading
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from services.executor.store import ActionStore
from shared.messages import StopReply
from tests.processes import ROOT, Network
from tests.tui.camera_frame import frame
from tests.tui.helpers import serve_actions, stage_world, teach
from tests.waiting import eventually

pytestmark = pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed")

HFPBD = str(Path(sys.executable).with_name("hfpbd"))


class Terminal:
    """A detached 120×40 tmux session on a private server socket, running one command."""

    def __init__(self, command: list[str]) -> None:
        self.socket = "hfpbd-test-" + uuid.uuid4().hex[:8]
        self._tmux("new-session", "-d", "-x", "120", "-y", "40", "-s", "ui", subprocess.list2cmdline(command))

    def _tmux(self, *args: str) -> str:
        return subprocess.run(
            ["tmux", "-L", self.socket, "-f", "/dev/null", *args],
            cwd=ROOT,
            check=True,
            capture_output=True,
            text=True,
            timeout=10,
        ).stdout

    def screen(self) -> str:
        return self._tmux("capture-pane", "-p", "-t", "ui")

    def type(self, *keys: str) -> None:
        self._tmux("send-keys", "-t", "ui", *keys)

    def wait_for(self, text: str, timeout: float = 30.0) -> str:
        """The screen once ``text`` is on it; fail showing the last screen seen."""
        return self.wait_until(lambda screen: text in screen, timeout, f"{text!r} on the terminal")

    def wait_until(self, shows: Callable[[str], bool], timeout: float, what: str) -> str:
        """The screen once ``shows(screen)`` holds; fail showing the last screen seen."""
        seen = [""]

        def showing() -> str:
            seen[0] = self.screen()
            return seen[0] if shows(seen[0]) else ""

        try:
            return eventually(showing, timeout, what)
        except AssertionError as exc:
            raise AssertionError(f"{exc}:\n{seen[0]}") from None

    def running(self) -> bool:
        return (
            subprocess.run(
                ["tmux", "-L", self.socket, "has-session", "-t", "ui"], capture_output=True, timeout=10
            ).returncode
            == 0
        )

    def close(self) -> None:
        subprocess.run(["tmux", "-L", self.socket, "kill-server"], capture_output=True, timeout=10)


@pytest.fixture
def terminal(network: Network) -> Iterator[Terminal]:
    # COLUMNS/LINES from the test runner's environment would override the real terminal size
    term = Terminal(["env", "-u", "COLUMNS", "-u", "LINES", HFPBD, "tui", *network.client_argv()])
    try:
        yield term
    finally:
        term.close()


def test_a_person_at_the_terminal(network: Network, terminal: Terminal) -> None:
    hub = network.hub
    heard: queue.Queue[dict[str, Any]] = queue.Queue()
    hub.subscribe(hub.keys.utterance, heard.put)
    stops: queue.Queue[dict[str, Any]] = queue.Queue()
    hub.serve(hub.keys.sim_control("stop"), lambda request: (stops.put(request), StopReply(ok=True, stopped=[]))[1])

    screen = terminal.wait_for("no service is running")
    assert "○ sim" in screen and "○ executor" in screen

    hub.declare_alive("nlu")
    terminal.wait_for("no executor: commands not carried out")
    assert "● nlu" in terminal.screen()

    terminal.type("move your right hand up", "Enter")
    assert heard.get(timeout=20)["text"] == "move your right hand up"
    terminal.wait_for("you   › move your right hand up")

    hub.publish(hub.keys.say, {"text": "Moving my right hand up.", "kind": "narration"})
    terminal.wait_for("robot › Moving my right hand up.")

    terminal.type("Escape")  # stop: the executor is not running, so the arms are stopped directly
    assert stops.get(timeout=20) == {"v": 1}
    terminal.wait_for("stopped the arms directly")

    terminal.type("C-q")
    eventually(lambda: not terminal.running(), 20, "the UI to quit on ctrl+q")
    assert not terminal.running(), "the UI did not quit on ctrl+q"


def test_the_camera_and_the_actions_at_the_terminal(network: Network, terminal: Terminal, tmp_path: Path) -> None:
    hub = network.hub
    world = stage_world(hub)
    store = ActionStore(tmp_path)
    teach(store)
    runs: list[tuple[int, int]] = []
    serve_actions(hub, store, runs)
    streaming = threading.Event()

    def camera() -> None:  # the simulator's head camera, 5 frames a second
        while not streaming.wait(0.2):
            hub.publish(hub.keys.cloud, frame())

    thread = threading.Thread(target=camera, daemon=True)
    thread.start()
    try:
        terminal.wait_for("● executor")
        terminal.type("F2")
        terminal.wait_for("world · head camera")
        screen = terminal.wait_until(lambda shown: shown.count("▀") >= 200, 30, "a camera picture")
        assert screen.count("▀") >= 200, f"no camera picture:\n{screen}"
        assert "the green box" in screen and "obj2" in screen  # the name over the picture, the id only in the table

        terminal.type("F4")
        terminal.wait_for("stack the cups")
        terminal.wait_for("tidy the box")
        terminal.type("Tab", "Down", "e")
        terminal.wait_for("executing action 1 from step 2")
        assert runs == [(1, 2)]
        terminal.type("F4")
        terminal.wait_for("conversation")
    finally:
        streaming.set()
        thread.join(timeout=5)
        del world
