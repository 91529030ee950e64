"""The conversation: what the user said and what the robot answered."""

from __future__ import annotations

from dataclasses import dataclass

from rich.text import Text
from textual.widgets import RichLog

# speaker/kind -> (prefix, style)
_STYLES: dict[str, tuple[str, str]] = {
    "user": ("you   › ", "bold"),
    "heard": ("heard › ", "italic"),  # what the speech service made of what was said
    "narration": ("robot › ", "green"),
    "info": ("robot › ", "cyan"),
    "answer": ("robot = ", "bold magenta"),  # a question answered: not narration, not an error
    "clarify": ("robot ? ", "bold yellow"),
    "error": ("robot ! ", "bold red"),
    "ui": ("      · ", "dim"),
    "warning": ("      ! ", "yellow"),
}


@dataclass(frozen=True)
class Line:
    """One entry of the conversation, kept so it can be searched and re-read."""

    kind: str
    text: str


class Conversation(RichLog):
    """A scrolling log of the dialog, each line marked by who said it and how."""

    DEFAULT_CSS = """
    Conversation { scrollbar-size-vertical: 1; }
    """

    def __init__(self, **kwargs: object) -> None:
        super().__init__(wrap=True, min_width=20, markup=False, highlight=False, **kwargs)  # type: ignore[arg-type]
        self.entries: list[Line] = []

    def add(self, kind: str, text: str) -> None:
        """Append a line; ``kind`` is 'user', 'heard', a ``dialog/say`` kind, 'answer', 'ui' or 'warning'."""
        prefix, style = _STYLES.get(kind, _STYLES["info"])
        self.entries.append(Line(kind, text))
        line = Text(prefix, style=style)
        line.append(text, style=style if kind != "user" else "")
        self.write(line)

    def texts(self, kind: str | None = None) -> list[str]:
        return [e.text for e in self.entries if kind is None or e.kind == kind]
