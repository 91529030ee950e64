"""The input line: history on up/down, completion from the NLU's vocabulary."""

from __future__ import annotations

from textual.binding import Binding
from textual.suggester import Suggester
from textual.widgets import Input

from tui.clarify import ClarifyPrompt


class VocabularySuggester(Suggester):
    """Completes a whole known phrase, else the word being typed.

    Phrases (e.g. "move your right hand", referring expressions) come first
    because they save the most keystrokes; single words complete the last
    word typed, preferring the shortest match.
    """

    def __init__(self) -> None:
        super().__init__(use_cache=False, case_sensitive=False)
        self.words: list[str] = []
        self.phrases: list[str] = []

    def learn(self, words: list[str] | None = None, phrases: list[str] | None = None) -> None:
        if words is not None:
            self.words = sorted({w.casefold() for w in words if w.strip()}, key=lambda w: (len(w), w))
        if phrases is not None:
            self.phrases = sorted({p.casefold() for p in phrases if p.strip()}, key=lambda p: (len(p), p))

    async def get_suggestion(self, value: str) -> str | None:
        return self.complete(value)

    def complete(self, value: str) -> str | None:
        if not value.strip():
            return None
        # a phrase may start anywhere a word starts: "... above the r" → "the red cup"
        starts = [0] + [i + 1 for i, c in enumerate(value) if c == " " and i + 1 < len(value)]
        for start in starts:
            tail = value[start:]
            for phrase in self.phrases:
                if phrase.startswith(tail) and len(phrase) > len(tail):
                    return value[:start] + phrase
        if value[-1].isspace():
            return None
        head, _, last = value.rpartition(" ")
        for word in self.words:
            if word.startswith(last) and len(word) > len(last):
                return f"{head} {word}" if head else word
        return None


class CommandInput(Input):
    """What the user types to the robot.

    Up/down walk the history of sent lines, except while a clarification is
    open: then they move through its answers, so the keyboard never has to
    leave the input line. Tab accepts the grey completion.
    """

    BINDINGS = [
        Binding("up", "arrow(-1)", "previous", show=False),
        Binding("down", "arrow(1)", "next", show=False),
        Binding("tab", "accept_completion", "complete", show=False),
    ]

    def __init__(self, prompt: ClarifyPrompt, **kwargs: object) -> None:
        self.vocabulary = VocabularySuggester()
        super().__init__(suggester=self.vocabulary, **kwargs)  # type: ignore[arg-type]
        self._prompt = prompt
        self.history: list[str] = []
        self._position = 0  # index into history; len(history) = the line being typed
        self._draft = ""

    def remember(self, line: str) -> None:
        """Add a sent line to the history (consecutive repeats once)."""
        if line and (not self.history or self.history[-1] != line):
            self.history.append(line)
        self._position = len(self.history)
        self._draft = ""

    def action_arrow(self, delta: int) -> None:
        if self._prompt.is_open:
            self._prompt.move(delta)
            return
        if not self.history:
            return
        if self._position == len(self.history):
            self._draft = self.value
        self._position = max(0, min(len(self.history), self._position + delta))
        self.value = self._draft if self._position == len(self.history) else self.history[self._position]
        self.cursor_position = len(self.value)

    def action_accept_completion(self) -> None:
        if self._suggestion and self.cursor_at_end:
            self.value = self._suggestion
            self.cursor_position = len(self.value)
        else:
            self.screen.focus_next()
