"""The action panel: the action being programmed, its steps, execution progress."""

from __future__ import annotations

from rich.text import Text
from textual.app import ComposeResult
from textual.containers import Vertical
from textual.widgets import Label, ProgressBar, Static

from shared.messages import Robot


class ActionPanel(Vertical):
    """Current action number, its steps in the user's words, and progress while executing."""

    def compose(self) -> ComposeResult:
        yield Label("no action yet", id="action-title")
        yield Static("", id="action-steps")
        yield ProgressBar(total=1, show_eta=False, id="action-progress")

    def show(self, robot: Robot) -> None:
        number = robot.action
        actions = robot.actions
        steps = robot.steps
        progress = robot.progress
        title = self.query_one("#action-title", Label)
        if number:
            title.update(f"action {number} of {max(len(actions), int(number))} · {len(steps)} step(s)")
        else:
            title.update("no action yet — say “create a new action”")
        current = progress.step if progress else None
        lines = Text()
        for n, step in enumerate(steps, start=1):
            running = current == n
            lines.append(f"{'▶' if running else ' '} {n}. {step}\n", style="bold yellow" if running else "")
        if not steps:
            lines.append("no steps recorded", style="dim")
        self.query_one("#action-steps", Static).update(lines)
        bar = self.query_one("#action-progress", ProgressBar)
        bar.display = progress is not None
        if progress:
            bar.update(total=max(1, progress.of or 1), progress=progress.step)
