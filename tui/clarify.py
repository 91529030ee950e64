"""The clarification prompt: the robot's question with its candidate answers.

The prompt never takes the keyboard away from the input line (typing must keep
working); the app forwards arrow keys, Enter and digits to it while it is
open, and the mouse can click an answer directly.
"""

from __future__ import annotations

from textual.app import ComposeResult
from textual.containers import Vertical
from textual.message import Message
from textual.widgets import Label, OptionList
from textual.widgets.option_list import Option


class ClarifyPrompt(Vertical):
    """A question and its numbered answers; hidden while no question is pending."""

    class Chosen(Message):
        """The user picked answer ``index`` (0-based) whose label is ``label``."""

        def __init__(self, index: int, label: str) -> None:
            super().__init__()
            self.index = index
            self.label = label

    def __init__(self, **kwargs: object) -> None:
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.candidates: list[str] = []
        self.question = ""

    def compose(self) -> ComposeResult:
        yield Label("", id="clarify-question")
        yield OptionList(id="clarify-options")

    @property
    def is_open(self) -> bool:
        return bool(self.candidates)

    def ask(self, question: str, candidates: list[str]) -> None:
        """Show a question; with no candidates nothing is shown (the dialog has the question)."""
        self.question = question
        self.candidates = list(candidates)
        self.query_one("#clarify-question", Label).update(
            f"{question}  [dim](number, ↑↓ Enter, click, or type your answer)[/dim]"
        )
        options = self.query_one("#clarify-options", OptionList)
        options.clear_options()
        options.add_options([Option(f"{n}. {label}", id=str(n - 1)) for n, label in enumerate(candidates, start=1)])
        options.highlighted = 0 if candidates else None
        self.set_class(self.is_open, "-open")

    def close(self) -> None:
        self.candidates = []
        self.question = ""
        self.query_one("#clarify-options", OptionList).clear_options()
        self.remove_class("-open")

    def move(self, delta: int) -> None:
        """Move the highlighted answer by ``delta``, wrapping around."""
        options = self.query_one("#clarify-options", OptionList)
        if not self.candidates:
            return
        current = options.highlighted if options.highlighted is not None else 0
        options.highlighted = (current + delta) % len(self.candidates)

    def choose_highlighted(self) -> None:
        highlighted = self.query_one("#clarify-options", OptionList).highlighted
        if highlighted is not None:
            self.choose(highlighted)

    def choose(self, index: int) -> bool:
        """Pick answer ``index`` (0-based); False when there is no such answer."""
        if not 0 <= index < len(self.candidates):
            return False
        self.post_message(self.Chosen(index, self.candidates[index]))
        return True

    def on_option_list_option_selected(self, event: OptionList.OptionSelected) -> None:
        event.stop()
        self.choose(event.option_index)
