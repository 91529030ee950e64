"""The head camera on screen: the picture drawn by textual-image, labels laid over it as text.

textual-image draws with a terminal graphics protocol (Sixel, Kitty's) where
the terminal has one and with coloured half-blocks everywhere else. Half-block
pictures arrive already drawn (``tui.camera`` runs textual-image's renderer on
a worker thread) and are only copied to the screen here. The labels are
ordinary Textual widgets on a layer above the picture, so they stay sharp
text however coarse the picture is; only the outlines and gripper marks are
drawn into the image.
"""

from __future__ import annotations

import sys
import time
from collections import deque

from rich.text import Text
from textual.app import ComposeResult
from textual.containers import Container
from textual.strip import Strip
from textual.widget import Widget
from textual.widgets import Static
from textual_image import widget as image_widgets
from textual_image._terminal import get_cell_size  # the cell size textual-image itself scales with
from textual_image.widget._base import Image as ImageWidget  # the base every drawing's widget class shares

from tui.camera import Label, Picture

# one class per choice of ``hfpbd tui --camera-drawing`` (tui.main.DRAWINGS names them without importing this)
DRAWINGS: dict[str, type[ImageWidget]] = {
    "auto": image_widgets.Image,
    "sixel": image_widgets.SixelImage,
    "tgp": image_widgets.TGPImage,
    "halfcell": image_widgets.HalfcellImage,
}
WAITING = "waiting for the head camera's picture (sim/cloud) — is the simulator running?"


def image_class(drawing: str) -> type[ImageWidget]:
    """The widget class for a drawing method; "auto" off a terminal (tests, pipes) means half-blocks.

    textual-image's own choice off a terminal is grey Unicode blocks, which
    would lose the colours people tell objects apart by.
    """
    chosen = DRAWINGS[drawing]
    if drawing == "auto" and not (sys.__stdout__ and sys.__stdout__.isatty()):
        return image_widgets.HalfcellImage
    if chosen is image_widgets.UnicodeImage:
        return image_widgets.HalfcellImage
    return chosen


def pixels_per_cell(kind: type[ImageWidget]) -> tuple[int, int]:
    """Image pixels one cell shows: two stacked for half-blocks, the cell's own pixels for graphics."""
    if issubclass(kind, image_widgets.HalfcellImage):
        return (1, 2)
    cell = get_cell_size()
    return (cell.width, cell.height)


def cell_shape() -> tuple[int, int]:
    """A terminal cell's size in pixels, as textual-image measured it (10 × 20 where it cannot ask)."""
    cell = get_cell_size()
    return (cell.width, cell.height)


class DrawnPicture(Widget):
    """Rows of a picture drawn elsewhere (``Picture.lines``), copied to the screen as they are."""

    def __init__(self, **kwargs: object) -> None:
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.lines: list[Strip] = []

    def show(self, lines: list[Strip]) -> None:
        self.lines = lines
        self.refresh()

    def render_line(self, y: int) -> Strip:
        return self.lines[y] if y < len(self.lines) else Strip.blank(self.size.width)


class CameraLabel(Static):
    """A name or gripper letter over the picture; remembers what it shows, to skip unchanged updates."""

    def __init__(self, **kwargs: object) -> None:
        super().__init__("", **kwargs)  # type: ignore[arg-type]
        self.spec: Label | None = None


class CameraView(Container):
    """The latest head-camera picture with object names and gripper letters over it."""

    def __init__(self, drawing: str = "auto", **kwargs: object) -> None:
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.image_kind = image_class(drawing)
        self.cell = cell_shape()
        self.per_cell = pixels_per_cell(self.image_kind)
        self.picture: Picture | None = None
        self._labels: list[CameraLabel] = []
        self.shown: deque[tuple[float, float]] = deque(maxlen=50)  # (when, UI seconds spent) per picture

    def compose(self) -> ComposeResult:
        yield Static(WAITING, id="camera-waiting")
        drawn_here = issubclass(self.image_kind, image_widgets.HalfcellImage)
        yield DrawnPicture(id="camera-image") if drawn_here else self.image_kind(id="camera-image")

    def on_mount(self) -> None:
        self.query_one("#camera-image").display = False

    def space(self) -> tuple[int, int]:
        """Cells available for the picture (columns, rows)."""
        return max(1, self.content_size.width), max(1, self.content_size.height)

    def fail(self, reason: str) -> None:
        """Say why there is no new picture; the next good frame replaces the message."""
        waiting = self.query_one("#camera-waiting", Static)
        waiting.update(reason)
        waiting.display = True
        self.query_one("#camera-image").display = False
        for label in self._labels:
            label.display = False

    def rate(self) -> tuple[float, float]:
        """Pictures per second over the recent ones, and the mean UI-thread milliseconds each took to show."""
        if len(self.shown) < 2:
            return 0.0, 0.0
        span = self.shown[-1][0] - self.shown[0][0]
        spent = sum(s for _, s in self.shown) / len(self.shown) * 1000
        return (len(self.shown) - 1) / span if span > 0 else 0.0, spent

    def show(self, picture: Picture) -> None:
        """Put a composed picture on screen (UI thread; the picture is already at its final size)."""
        # the UI thread's own CPU time: wall time would also count its waits for a core and for the
        # interpreter lock, which the bus and composing threads hold on a loaded machine
        start = time.thread_time()
        self._show(picture)
        self.shown.append((time.monotonic(), time.thread_time() - start))

    def _show(self, picture: Picture) -> None:
        self.picture = picture
        self.query_one("#camera-waiting", Static).display = False
        image = self.query_one("#camera-image")
        image.styles.width = picture.columns
        image.styles.height = picture.rows
        if isinstance(image, DrawnPicture) and picture.lines is not None:
            image.show(picture.lines)
        else:  # a textual-image widget: the terminal's graphics protocol draws it
            image.image = picture.image  # type: ignore[attr-defined]
        image.display = True
        while len(self._labels) < len(picture.labels):
            label = CameraLabel(classes="camera-label")
            self._labels.append(label)
            self.mount(label)
        for label, spec in zip(self._labels[: len(picture.labels)], picture.labels, strict=True):
            if label.spec == spec and label.display:
                continue  # unchanged: updating it would lay the screen out again for nothing
            label.spec = spec
            text = spec.text[: max(1, picture.columns - spec.column)]
            label.update(Text(text, style=spec.style))
            label.styles.offset = (min(spec.column, picture.columns - 1), min(spec.row, picture.rows - 1))
            label.styles.width = len(text)
            label.display = True
        for label in self._labels[len(picture.labels) :]:
            label.display = False
