"""The hands-free programming dialog in a terminal.

A person types what they would say to the robot ("move your right hand above
the red cup", "pick it up", "execute"); the conversation shows what the robot
answers, and the panels show what it sees and does. The app talks to the
services only over the bus (see ``tui.bridge``), so it starts and stays usable
with none of them running, and picks them up as they appear.
"""

from __future__ import annotations

import functools
import io
import logging
import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any, TypeVar

from PIL import Image
from textual import work
from textual.app import App, ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical
from textual.screen import Screen
from textual.widgets import Footer, Header, Input
from textual.worker import get_current_worker

from shared.bus import BusTimeout, RemoteError
from shared.config import SessionOptions
from shared.messages import Cloud, Robot
from tui import events
from tui.action_panel import ActionPanel
from tui.actions_screen import ActionsScreen
from tui.bridge import PROBES, Bridge, Poster
from tui.camera import compose as compose_picture
from tui.camera_view import CameraView
from tui.clarify import ClarifyPrompt
from tui.command_input import CommandInput
from tui.conversation import Conversation
from tui.overview_screen import OverviewScreen
from tui.robot_panel import RobotPanel
from tui.status_bar import CONSEQUENCES, StatusBar
from tui.world import WorldView
from tui.world_panel import TableCanvas, WorldPanel

log = logging.getLogger("hfpbd.tui")

RECONNECT_SECONDS = 3.0
CAMERA_LOG_EVERY = 50  # pictures between two lines in the log about the camera's refresh rate
NO_SPEECH = (
    "push-to-talk needs the speech service, which is not running (start it: hfpbd speech); typing works as always"
)
T = TypeVar("T")


Handler = TypeVar("Handler", bound=Callable[..., None])


def while_running(handler: Handler) -> Handler:
    """Drop bus news that arrives while the app shuts down: its widgets are already gone."""

    @functools.wraps(handler)
    def guarded(app: PbdApp, *args: Any) -> None:
        if app.is_running:
            handler(app, *args)

    return guarded  # type: ignore[return-value]


class PbdApp(App[None]):
    """Program a two-armed robot by talking to it."""

    CSS_PATH = "app.tcss"
    # the layout adapts below 110 columns and below 36 rows (app.tcss); it works from 80 × 24 up
    HORIZONTAL_BREAKPOINTS = [(0, "-narrow"), (110, "-wide")]
    VERTICAL_BREAKPOINTS = [(0, "-short"), (36, "-tall")]
    TITLE = "hands-free PbD"
    BINDINGS = [
        Binding("escape", "stop", "Stop robot", priority=True),
        Binding("f2", "camera", "Camera", priority=True),
        Binding("f3", "overview", "Overview", priority=True),
        Binding("f4", "actions", "Actions", priority=True),
        Binding("f5", "execute", "Execute", priority=True),
        Binding("f6", "new_action", "New action", priority=True),
        Binding("f7", "switch_action('previous')", "Prev action", priority=True),
        Binding("f8", "switch_action('next')", "Next action", priority=True),
        Binding("f9", "talk", "Talk", priority=True),
        Binding("ctrl+q", "quit", "Quit", priority=True),
    ]

    def __init__(
        self,
        options: SessionOptions,
        *,
        probe_seconds: float | None = 2.0,
        camera_drawing: str = "auto",
        bridge: Callable[[SessionOptions, Poster], Bridge] = Bridge,
    ) -> None:
        """``probe_seconds`` is how often latencies are measured (None: never); ``camera_drawing`` is
        how pictures are drawn (``tui.camera_view.DRAWINGS``: a graphics protocol or half-blocks);
        ``bridge`` makes the app's link to the bus, so that whoever drives the app can choose it."""
        super().__init__()
        self.camera_drawing = camera_drawing
        self._cloud: Cloud | None = None  # newest camera frame not yet composed
        self._last_cloud: Cloud | None = None
        self._composing = False
        self._pictures = 0
        self._actions_seen: tuple[Any, ...] = ()
        self.options = options
        self.bridge = bridge(options, self)
        self.world = WorldView()
        self.probe_seconds = probe_seconds
        self.sub_title = f"robot {options.namespace!r}"
        self._lost: set[str] = set()
        self._phrases: list[str] = []

    def compose(self) -> ComposeResult:
        prompt = ClarifyPrompt(id="clarify")
        yield Header()
        with Horizontal(id="main"):
            yield Conversation(id="conversation")
            with Vertical(id="side"):
                yield WorldPanel(self.camera_drawing, id="world")
                with Horizontal(id="panels"):
                    yield RobotPanel(id="robot")
                    yield ActionPanel(id="action")
        yield prompt
        yield CommandInput(
            prompt, id="input", placeholder="tell the robot, e.g. “move your right hand above the red cup”"
        )
        yield StatusBar(id="status")
        yield Footer()

    def on_mount(self) -> None:
        self.main.query_one("#conversation").border_title = "conversation"
        self.main.query_one("#robot").border_title = "robot"
        self.main.query_one("#action").border_title = "action"
        self.main.query_one("#clarify").border_title = "the robot asks"
        self.main.query_one(CommandInput).focus()
        self.main.query_one(StatusBar).set_connection(False, f"connecting to {self._where()}…")
        self.main.query_one(WorldPanel).show_view("map")
        self._refresh_world()
        self.main.query_one(ActionPanel).show(Robot())
        self.connect()
        if self.probe_seconds:
            self.set_interval(self.probe_seconds, self._probe_alive)

    @property
    def main(self) -> Screen[Any]:
        """The programming screen, even while the actions or overview screen is on top of it."""
        return self.screen_stack[0] if self.screen_stack else self.screen

    def on_unmount(self) -> None:
        self.bridge.close()

    def _where(self) -> str:
        endpoints = self.options.connect or self.options.listen
        return ", ".join(endpoints) if endpoints else "the local network"

    # -- connection ----------------------------------------------------------
    @work(thread=True, exclusive=True, group="connect")
    def connect(self) -> None:
        try:
            self.bridge.open()
        except Exception as exc:  # zenoh raises its own error type for every failure
            self.post_message(events.BusUnavailable(str(exc).split(" at ")[0]))

    @while_running
    def on_bus_unavailable(self, event: events.BusUnavailable) -> None:
        self.main.query_one(StatusBar).set_connection(
            False, f"cannot reach {self._where()}: {event.reason} — retrying every {RECONNECT_SECONDS:g} s"
        )
        self.set_timer(RECONNECT_SECONDS, self.connect)

    @while_running
    def on_bus_connected(self, _event: events.BusConnected) -> None:
        self.main.query_one(StatusBar).set_connection(True, f"on {self._where()}")
        if self.main.query_one(WorldPanel).camera_shown:  # the camera was asked for before the bus was up
            self.bridge.watch_camera()

    @while_running
    def on_presence(self, event: events.Presence) -> None:
        self.main.query_one(StatusBar).set_alive(event.service, event.alive)
        conversation = self.main.query_one(Conversation)
        if not event.alive and event.service == "speech":
            self.main.query_one(StatusBar).set_talking(False)
        if not event.alive and event.service in CONSEQUENCES:
            self._lost.add(event.service)
            conversation.add("warning", f"{event.service} stopped: {CONSEQUENCES[event.service]} until it is back")
        elif event.alive and event.service in self._lost:
            self._lost.discard(event.service)
            conversation.add("ui", f"{event.service} is back")
        if event.alive and event.service == "nlu":
            self.load_vocabulary()
            self.describe_objects()

    # -- what the services say -----------------------------------------------
    @while_running
    def on_said(self, event: events.Said) -> None:
        """Show what the robot says; an answer (a line with a topic) in its own style.

        Answers are shown from this spoken copy and never from ``nlu/result``
        (see ``on_understood``): the two travel apart and either may come
        first, so showing one source only is what keeps an answer to one line.
        """
        self.main.query_one(Conversation).add("answer" if event.topic else event.kind, event.text)
        if event.kind == "clarify" and event.candidates:
            self.main.query_one(ClarifyPrompt).ask(event.text, event.candidates)

    @while_running
    def on_understood(self, event: events.Understood) -> None:
        result = event.result
        if result.kind != "command":  # a clarification or an answer shows from its dialog/say line
            return
        self.main.query_one(ClarifyPrompt).close()
        args: dict[str, Any] = result.args or {}
        object_id = args.get("object")
        if isinstance(object_id, str):
            self.world.highlighted = object_id
            self._refresh_world()
        shown = ", ".join(f"{name}={self._named(name, value)}" for name, value in args.items())
        self.main.query_one(Conversation).add("ui", f"understood: {result.procedure}({shown})")

    def _named(self, name: str, value: Any) -> str:
        """An argument as the user reads it: objects by their descriptions, never by their ids."""
        if name in ("object", "landmark", "carried") and isinstance(value, str):
            seen = self.world.objects.get(value)
            if value in self.world.descriptions or seen is None:
                return self.world.name_of(value) if seen is not None else "an object not in view"
            return f"the {seen.color} {seen.type}"  # not described yet: by its colour and kind
        if isinstance(value, dict):
            return "{" + ", ".join(f"{k}: {self._named(k, v)}" for k, v in value.items()) + "}"
        if name == "each" and isinstance(value, list):
            return "[" + ", ".join(self._named("object", v) for v in value) + "]"
        return str(value)

    @while_running
    def on_objects_seen(self, event: events.ObjectsSeen) -> None:
        before = {k: v.position for k, v in self.world.objects.items()}
        self.world.objects = {o.id: o for o in event.objects}
        self._refresh_world()
        if {k: v.position for k, v in self.world.objects.items()} != before:
            self.describe_objects()

    @while_running
    def on_executor_changed(self, event: events.ExecutorChanged) -> None:
        self.world.robot = event.robot
        self.world.reach = event.reach
        self._refresh_world()
        self.main.query_one(ActionPanel).show(event.robot)
        seen = (event.robot.action, tuple(event.robot.actions))
        if seen != self._actions_seen:
            self._actions_seen = seen
            if isinstance(self.screen, ActionsScreen):
                self.screen.refresh_list()

    @while_running
    def on_cloud_seen(self, event: events.CloudSeen) -> None:
        if not self.main.query_one(WorldPanel).camera_shown:
            return
        self._cloud = self._last_cloud = event.cloud
        if not self._composing:
            self._composing = True
            self._compose_newest()

    def _compose_newest(self) -> None:
        view = self.main.query_one(CameraView)
        self.compose_camera(*view.space(), view.cell, view.per_cell, self.main.query_one(WorldPanel).close_up)

    @while_running
    def on_camera_pictured(self, event: events.CameraPictured) -> None:
        self._composing = False
        view = self.main.query_one(CameraView)
        view.show(event.picture)
        self._pictures += 1
        if self._pictures % CAMERA_LOG_EVERY == 0:
            rate, spent = view.rate()
            log.info("camera: %.1f pictures/s, %.2f ms on the UI thread per picture", rate, spent)
        if self._cloud is not None and self.main.query_one(WorldPanel).camera_shown:
            self._composing = True
            self._compose_newest()

    @while_running
    def on_camera_failed(self, event: events.CameraFailed) -> None:
        self._composing = False
        self.main.query_one(CameraView).fail(event.reason)

    @while_running
    def on_overview_taken(self, event: events.OverviewTaken) -> None:
        self.push_screen(OverviewScreen(event.image, self.options.namespace, self.camera_drawing))

    @while_running
    def on_sim_moved(self, event: events.SimMoved) -> None:
        self.world.ee = event.ee
        self.world.grippers = event.grippers
        self.main.query_one(TableCanvas).show(self.world)
        self.main.query_one(RobotPanel).show(self.world)

    @while_running
    def on_described(self, event: events.Described) -> None:
        self.world.descriptions = event.descriptions
        self._refresh_world()
        self.main.query_one(CommandInput).vocabulary.learn(phrases=[*self._phrases, *event.descriptions.values()])

    @while_running
    def on_vocabulary_loaded(self, event: events.VocabularyLoaded) -> None:
        self._phrases = event.phrases
        phrases = [*event.phrases, *self.world.descriptions.values()]
        self.main.query_one(CommandInput).vocabulary.learn(event.words, phrases)

    @while_running
    def on_latency(self, event: events.Latency) -> None:
        self.main.query_one(StatusBar).set_latency(event.service, event.seconds)

    @while_running
    def on_heard(self, event: events.Heard) -> None:
        sure = f"  ({event.sure:.0%} sure)" if event.sure is not None else ""
        self.main.query_one(Conversation).add("heard", f"{event.text}{sure}")

    @while_running
    def on_talking(self, event: events.Talking) -> None:
        self.main.query_one(StatusBar).set_talking(event.listening)

    @while_running
    def on_request_failed(self, event: events.RequestFailed) -> None:
        self.main.query_one(Conversation).add("error", f"{event.what} failed: {event.reason}")

    def _refresh_world(self) -> None:
        self.main.query_one(WorldPanel).show(self.world)
        self.main.query_one(RobotPanel).show(self.world)

    # -- what the user does --------------------------------------------------
    def on_input_submitted(self, event: Input.Submitted) -> None:
        line = event.value.strip()
        entry = self.main.query_one(CommandInput)
        entry.value = ""
        prompt = self.main.query_one(ClarifyPrompt)
        if prompt.is_open and not line:
            prompt.choose_highlighted()
            return
        if prompt.is_open and line.isdigit():
            if not prompt.choose(int(line) - 1):
                self.main.query_one(Conversation).add(
                    "warning", f"there is no answer {line}: choose 1 to {len(prompt.candidates)}, or say what you mean"
                )
            return
        if not line:
            return
        entry.remember(line)
        prompt.close()
        self._send(line, line)

    def on_clarify_prompt_chosen(self, event: ClarifyPrompt.Chosen) -> None:
        self.main.query_one(ClarifyPrompt).close()
        self._send(f"{event.index + 1}. {event.label}", event.label, event.index)

    def _send(self, shown: str, text: str, choice: int | None = None) -> None:
        conversation = self.main.query_one(Conversation)
        conversation.add("user", shown)
        if not self.bridge.connected:
            conversation.add(
                "warning", "not connected to the robot yet: this was not sent, say it again once connected"
            )
            return
        self.bridge.say(text, choice)
        if "nlu" not in self.main.query_one(StatusBar).alive:
            conversation.add("warning", "the language service (nlu) is not running: nobody understands this yet")

    def action_stop(self) -> None:
        self.main.query_one(Conversation).add("user", "[Esc] stop")
        self.stop_robot()

    def action_execute(self) -> None:
        self._direct("execute", {}, "[F5] execute")

    def action_new_action(self) -> None:
        self._direct("create_action", {}, "[F6] new action")

    def action_switch_action(self, target: str) -> None:
        self._direct("switch_action", {"target": target}, f"[{'F7' if target == 'previous' else 'F8'}] {target} action")

    def action_camera(self) -> None:
        """Step from the top-down map to the head camera, its close-up, and back."""
        panel = self.main.query_one(WorldPanel)
        view = panel.next_view()
        if view == "camera" and self.bridge.connected:
            self.bridge.watch_camera()
        elif view == "camera":
            self.main.query_one(Conversation).add("warning", "not connected yet: the camera shows once connected")
        if view != "map" and self._last_cloud is not None and not self._composing:
            self._cloud = self._last_cloud  # redraw the frame in hand at once, not at the next one
            self._composing = True
            self._compose_newest()

    def action_overview(self) -> None:
        if isinstance(self.screen, OverviewScreen):
            self.screen.dismiss()
            return
        self.main.query_one(Conversation).add("user", "[F3] overview picture")
        self.take_overview()

    def action_actions(self) -> None:
        """Open the actions screen, or close it (Esc stays "stop the robot" on every screen)."""
        if isinstance(self.screen, ActionsScreen):
            self.screen.dismiss()
        elif not isinstance(self.screen, OverviewScreen):
            self.push_screen(ActionsScreen(self.bridge, self.options.namespace))

    def action_talk(self) -> None:
        """Push-to-talk as a toggle: terminals report key presses, never releases."""
        bar = self.main.query_one(StatusBar)
        if "speech" not in bar.alive:
            self.main.query_one(Conversation).add("warning", NO_SPEECH)
            return
        self.push_to_talk(not bar.talking)

    def _direct(self, procedure: str, args: dict[str, Any], shown: str) -> None:
        self.main.query_one(Conversation).add("user", shown)
        self.run_command(procedure, args)

    # -- blocking requests, off the event loop -------------------------------
    @work(thread=True, group="stop")
    def stop_robot(self) -> None:
        try:
            message = self.bridge.stop()
            self.post_message(events.Said(message, "info", []))
        except (BusTimeout, RemoteError, ConnectionError) as exc:
            self.post_message(events.RequestFailed("stop", _reason(exc, "robot")))

    @work(thread=True, group="command")
    def run_command(self, procedure: str, args: dict[str, Any]) -> None:
        try:
            self.bridge.command(procedure, args)
        except (BusTimeout, RemoteError, ConnectionError) as exc:
            self.post_message(events.RequestFailed(procedure.replace("_", " "), _reason(exc, "executor")))

    @work(thread=True, exclusive=True, group="talk")
    def push_to_talk(self, on: bool) -> None:
        try:
            self.post_message(events.Talking(self.bridge.talk(on)))
        except (BusTimeout, RemoteError, ConnectionError) as exc:
            self.post_message(events.Talking(False))  # a speech service that does not answer is not listening
            self.post_message(events.RequestFailed("push-to-talk", _reason(exc, "speech service")))

    @work(thread=True, group="camera")
    def compose_camera(
        self, columns: int, rows: int, cell: tuple[int, int], per_cell: tuple[int, int], close_up: bool
    ) -> None:
        """Compose the newest frame for the camera view (scaling and drawing stay off the UI thread)."""
        cloud, self._cloud = self._cloud, None
        if cloud is None:
            return
        try:
            picture = compose_picture(cloud, replace(self.world), columns, rows, cell, per_cell, close_up)
        except (ValueError, TypeError, IndexError, KeyError) as exc:  # a frame that passed the schema but not drawing
            log.warning("camera frame not drawn: %s", exc)
            self.post_message(events.CameraFailed(f"the last camera frame could not be drawn ({exc})"))
            return
        self.post_message(events.CameraPictured(picture))

    @work(thread=True, exclusive=True, group="overview")
    def take_overview(self) -> None:
        try:
            png = self.bridge.snapshot()
        except (BusTimeout, RemoteError, ConnectionError) as exc:
            self.post_message(events.RequestFailed("the overview picture", _reason(exc, "simulator")))
            return
        try:
            image = Image.open(io.BytesIO(png)).convert("RGB")
        except OSError as exc:  # Pillow's error for bytes that are no picture
            self.post_message(events.RequestFailed("the overview picture", f"the simulator sent no PNG ({exc})"))
            return
        self.post_message(events.OverviewTaken(image))

    @work(thread=True, exclusive=True, group="vocabulary")
    def load_vocabulary(self) -> None:
        vocabulary = _patiently(self.bridge.vocabulary)
        if vocabulary is not None:  # completion is a convenience: without it typing still works
            self.post_message(events.VocabularyLoaded(*vocabulary))

    @work(thread=True, exclusive=True, group="describe")
    def describe_objects(self) -> None:
        """Ask the NLU for referring expressions, retrying briefly while it catches up on new objects."""
        worker = get_current_worker()
        for _attempt in range(4):
            descriptions = _patiently(self.bridge.describe)
            if descriptions is None or worker.is_cancelled:
                return
            self.post_message(events.Described(descriptions))
            if set(self.world.objects) <= set(descriptions):
                return
            time.sleep(0.5)

    def _probe_alive(self) -> None:
        bars = self.main.query(StatusBar)  # empty while the screen is being torn down
        if self.bridge.connected and bars:
            self.probe(sorted(bars.first().alive & set(PROBES)))

    @work(thread=True, exclusive=True, group="probe")
    def probe(self, services: list[str]) -> None:
        for service in services:
            if get_current_worker().is_cancelled:
                return
            try:
                seconds = self.bridge.ping(service)
            except ConnectionError:
                return
            self.post_message(events.Latency(service, seconds))


def _patiently(request: Callable[[], T], attempts: int = 6, pause: float = 0.5) -> T | None:
    """Retry a request for a few seconds: a service's liveliness token can
    arrive before its queryables are known here (Zenoh propagates them
    separately), so the first request right after it appears may find no one.
    """
    for attempt in range(attempts):
        try:
            return request()
        except BusTimeout:
            if attempt + 1 < attempts:
                time.sleep(pause)
        except (RemoteError, ConnectionError):
            return None
    return None


def _reason(exc: Exception, service: str) -> str:
    if isinstance(exc, BusTimeout):
        return f"the {service} did not answer (is it running?)"
    return str(exc)
