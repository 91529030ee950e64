"""The actions screen: every programmed action of this robot, and its steps in the user's words.

Everything here goes through the executor's ``executor/control/actions``
queryable of the robot's namespace, so the list is the one that robot
replays, and a change made here is seen by every other screen at once
(the executor republishes its state after each change). Deleting asks for
the same key a second time: one stray key press must not lose a program.
Esc keeps its meaning from the main screen (stop the robot); F4 or q closes.
"""

from __future__ import annotations

import time
from typing import Any

from rich.text import Text
from textual import events, on, work
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical
from textual.message import Message
from textual.screen import Screen
from textual.widgets import DataTable, Footer, Header, Input, Static

from shared.bus import BusTimeout, RemoteError
from shared.messages import ActionList, ActionRenamed, ActionSummary, Reply
from tui.bridge import Bridge


class ActionsReplied(Message):
    """The executor answered a request made on this screen."""

    def __init__(self, request: dict[str, Any], reply: Reply) -> None:
        super().__init__()
        self.request = request
        self.reply = reply


class ActionsFailed(Message):
    """A request made on this screen was refused or not answered; ``reason`` says why."""

    def __init__(self, request: dict[str, Any], reason: str) -> None:
        super().__init__()
        self.request = request
        self.reason = reason


def created_text(created: Any) -> str:
    """Local date and time an action was created, to the minute."""
    if not isinstance(created, (int, float)):
        return "—"
    return time.strftime("%Y-%m-%d %H:%M", time.localtime(created))


class ActionsScreen(Screen[None]):
    """List, rename, delete and run actions; show, delete and move their steps."""

    BINDINGS = [
        Binding("q", "close", "Back"),
        Binding("r", "rename", "Rename"),
        Binding("d", "delete_action", "Delete"),
        Binding("x", "delete_step", "Del step"),
        Binding("[", "move_step(-1)", "Step ↑"),
        Binding("]", "move_step(1)", "Step ↓"),
        Binding("e", "execute", "Run from step"),
    ]

    def __init__(self, bridge: Bridge, namespace: str) -> None:
        super().__init__()
        self.bridge = bridge
        self.namespace = namespace
        self.actions: list[ActionSummary] = []
        self._armed: tuple[str, int, int] | None = None  # a delete waiting for its second key press
        self._listed = False

    def compose(self) -> ComposeResult:
        yield Header()
        with Horizontal(id="actions-body"):
            with Vertical(id="actions-list"):
                yield DataTable(id="actions-table", cursor_type="row", zebra_stripes=True)
                yield Input(placeholder="new name (Enter; an empty name keeps the old one)", id="actions-rename")
            yield DataTable(id="steps-table", cursor_type="row", zebra_stripes=True)
        yield Static("", id="actions-note")
        yield Footer()

    def on_mount(self) -> None:
        self.sub_title = f"actions of robot {self.namespace!r}"
        self.query_one("#actions-list").border_title = "actions"
        self.query_one("#steps-table").border_title = "steps, as you said them"
        table = self.query_one("#actions-table", DataTable)
        table.add_column(" ", key="current", width=1)
        table.add_column("#", key="number")
        table.add_column("name", key="name")
        table.add_column("steps", key="steps")
        table.add_column("created", key="created")
        steps = self.query_one("#steps-table", DataTable)
        steps.add_column("#", key="number")
        steps.add_column("step", key="words")
        self.query_one("#actions-rename", Input).display = False
        table.focus()
        self.note("loading the actions…")
        self.ask({"op": "list"})

    # -- what is selected ------------------------------------------------------
    def selected_action(self) -> ActionSummary | None:
        table = self.query_one("#actions-table", DataTable)
        if not self.actions or table.cursor_row >= len(self.actions):
            return None
        return self.actions[table.cursor_row]

    def selected_step(self) -> int:
        """The highlighted step (1-based); 1 when the steps list was never visited."""
        return self.query_one("#steps-table", DataTable).cursor_row + 1

    def note(self, text: str, style: str = "") -> None:
        self.query_one("#actions-note", Static).update(Text(text, style=style))

    # -- showing ---------------------------------------------------------------
    def show_list(self, actions: list[ActionSummary]) -> None:
        """Redraw the actions table, keeping the cursor on the same row where it still exists."""
        self.actions = actions
        table = self.query_one("#actions-table", DataTable)
        row = table.cursor_row
        table.clear()
        for action in actions:
            table.add_row(
                Text("▶" if action.current else "", style="bold yellow"),
                str(action.number),
                action.name or Text("(unnamed)", style="dim"),
                str(action.steps),
                created_text(action.created),
                key=str(action.number),
            )
        if actions:
            table.move_cursor(row=min(row, len(actions) - 1))
        self.show_steps()

    def show_steps(self) -> None:
        steps = self.query_one("#steps-table", DataTable)
        row = steps.cursor_row
        steps.clear()
        action = self.selected_action()
        if action is None:
            self.note("no actions yet: say “create a new action”, then teach it some steps")
            return
        words = action.words
        for n, said in enumerate(words, start=1):
            steps.add_row(str(n), said, key=str(n))
        if words:
            steps.move_cursor(row=min(row, len(words) - 1))

    @on(DataTable.RowHighlighted, "#actions-table")
    def _action_highlighted(self) -> None:
        self._armed = None
        self.show_steps()

    # -- keys --------------------------------------------------------------------
    def action_close(self) -> None:
        self.dismiss()

    def action_rename(self) -> None:
        action = self.selected_action()
        if action is None:
            return
        rename = self.query_one("#actions-rename", Input)
        rename.value = action.name or ""
        rename.display = True
        rename.focus()

    @on(Input.Submitted, "#actions-rename")
    def _renamed(self, event: Input.Submitted) -> None:
        event.input.display = False
        self.query_one("#actions-table").focus()
        action = self.selected_action()
        name = event.value.strip()
        if action is None or not name or name == action.name:
            self.note("name kept")
            return
        self.ask({"op": "rename", "number": action.number, "name": name})

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        """Letter keys belong to the name being typed while renaming."""
        if action in ("close", "rename", "delete_action", "delete_step", "move_step", "execute"):
            return not self.query_one("#actions-rename", Input).display
        return True

    def action_delete_action(self) -> None:
        action = self.selected_action()
        if action is None:
            return
        if self._confirmed("action", action.number, 0):
            self.ask({"op": "delete", "number": action.number})
            return
        self.note(
            f"press d again to delete action {action.number} ({_name(action)}, {action.steps} steps); "
            "any other key keeps it",
            "bold yellow",
        )

    def action_delete_step(self) -> None:
        action = self.selected_action()
        if action is None or not action.steps:
            return
        step = self.selected_step()
        if self._confirmed("step", action.number, step):
            self.ask({"op": "delete_step", "number": action.number, "step": step})
            return
        self.note(
            f"press x again to delete step {step} of action {action.number} "
            f"(“{action.words[step - 1]}”); any other key keeps it",
            "bold yellow",
        )

    def action_move_step(self, by: int) -> None:
        action = self.selected_action()
        if action is None or not action.steps:
            return
        step = self.selected_step()
        to = step + by
        if not 1 <= to <= action.steps:
            self.note(f"step {step} is already the {'first' if by < 0 else 'last'}")
            return
        self.query_one("#steps-table", DataTable).move_cursor(row=to - 1)
        self.ask({"op": "move_step", "number": action.number, "step": step, "to": to})

    def action_execute(self) -> None:
        action = self.selected_action()
        if action is None:
            return
        if not action.steps:
            self.note(f"action {action.number} has no steps to execute yet", "bold red")
            return
        self.ask({"op": "execute", "number": action.number, "step": self.selected_step()})

    def _confirmed(self, what: str, number: int, step: int) -> bool:
        """True on the second press of the same delete; the first press only arms it."""
        armed, self._armed = self._armed, (what, number, step)
        if armed == (what, number, step):
            self._armed = None
            return True
        return False

    def on_key(self, event: events.Key) -> None:
        """Any key but the two delete keys disarms a pending delete."""
        if event.key not in ("d", "x"):
            self._armed = None

    # -- requests -----------------------------------------------------------------
    @work(thread=True, group="actions")
    def ask(self, request: dict[str, Any]) -> None:
        try:
            reply = self.bridge.actions(request)
        except BusTimeout:
            self.post_message(ActionsFailed(request, "the executor did not answer (is it running?)"))
        except (RemoteError, ConnectionError) as exc:
            self.post_message(ActionsFailed(request, str(exc)))
        else:
            self.post_message(ActionsReplied(request, reply))

    def on_actions_replied(self, event: ActionsReplied) -> None:
        op, reply = event.request["op"], event.reply
        if op == "list":
            first = not self._listed
            self._listed = True
            assert isinstance(reply, ActionList)
            self.show_list(reply.actions)
            if first and self.actions:  # later lists follow a change, whose note stays
                self.note(f"{len(self.actions)} action(s); the current one is marked ▶")
            return
        number = event.request.get("number")
        done = {
            "rename": f"renamed action {number} to “{reply.name if isinstance(reply, ActionRenamed) else ''}”",
            "delete": f"deleted action {number}; later actions moved down by one",
            "delete_step": f"deleted step {event.request.get('step')} of action {number}",
            "move_step": f"moved step {event.request.get('step')} of action {number} to {event.request.get('to')}",
            "execute": f"executing action {number} from step {event.request.get('step')}",
        }
        self.note(done.get(op, "done"), "green")
        self.ask({"op": "list"})

    def on_actions_failed(self, event: ActionsFailed) -> None:
        self.note(f"{event.request['op'].replace('_', ' ')} failed: {event.reason}", "bold red")
        if event.request["op"] == "move_step":
            self.ask({"op": "list"})  # the cursor moved ahead of the list: put it back where the steps are

    def refresh_list(self) -> None:
        """The executor's state changed (a step recorded, an action created): list again."""
        self.ask({"op": "list"})


def _name(action: ActionSummary) -> str:
    return f"“{action.name}”" if action.name else "unnamed"
