"""The status bar: which services are up, how fast they answer, and what cannot work."""

from __future__ import annotations

from rich.text import Text
from textual.widgets import Static

REQUIRED = ("sim", "perception", "nlu", "executor")
OPTIONAL = ("speech",)

# What the user loses while a service is missing, in their terms.
CONSEQUENCES: dict[str, str] = {
    "sim": "nothing moves",
    "perception": "objects unseen",
    "nlu": "commands not understood",
    "executor": "commands not carried out",
}


class StatusBar(Static):
    """Presence from liveliness tokens, round-trip times from probe requests."""

    def __init__(self, **kwargs: object) -> None:
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.alive: set[str] = set()
        self.latency: dict[str, float | None] = {}
        self.connection = "connecting…"
        self.connected = False
        self.talking = False  # push-to-talk is on: the speech service collects what is said

    def set_connection(self, connected: bool, text: str) -> None:
        self.connected = connected
        self.connection = text
        self._redraw()

    def set_alive(self, service: str, alive: bool) -> None:
        (self.alive.add if alive else self.alive.discard)(service)
        if not alive:
            self.latency.pop(service, None)
        self._redraw()

    def set_talking(self, talking: bool) -> None:
        self.talking = talking
        self._redraw()

    def set_latency(self, service: str, seconds: float | None) -> None:
        self.latency[service] = seconds
        self._redraw()

    def missing(self) -> list[str]:
        return [s for s in REQUIRED if s not in self.alive]

    def summary(self) -> str:
        """The bar as plain text (what a screen reader or a test reads)."""
        return self.render_text().plain

    def render_text(self) -> Text:
        line = Text()
        if self.talking:
            line.append(" listening… (F9 when done) ", style="bold reverse")
            line.append("  ")
        line.append(self.connection, style="green" if self.connected else "bold red")
        for service in (*REQUIRED, *OPTIONAL, *sorted(self.alive - set(REQUIRED) - set(OPTIONAL))):
            up = service in self.alive
            if not up and service in OPTIONAL:
                continue
            line.append("  ")
            line.append("● " if up else "○ ", style="green" if up else "red")
            line.append(service, style="" if up else "red")
            seconds = self.latency.get(service)
            if up and seconds is not None:
                line.append(f" {seconds * 1000:.0f} ms", style="dim")
        missing = self.missing()
        if len(missing) == len(REQUIRED):
            line.append("\n")
            line.append(
                "⚠ no service is running: commands are neither understood nor carried out (start them: hfpbd up)",
                style="yellow",
            )
        elif missing:
            reasons = " · ".join(f"no {s}: {CONSEQUENCES[s]}" for s in missing)
            line.append("\n")
            line.append(f"⚠ {reasons}", style="yellow")
        return line

    def _redraw(self) -> None:
        self.update(self.render_text())
