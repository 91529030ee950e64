"""The whole robot at its table, from the simulator's overview camera, over the main screen."""

from __future__ import annotations

from PIL import Image
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical
from textual.screen import ModalScreen
from textual.widgets import Static

from tui.camera import fit_cells
from tui.camera_view import cell_shape, image_class, pixels_per_cell


class OverviewScreen(ModalScreen[None]):
    """One picture, as large as the terminal allows; F3, Enter or q closes it (Esc still stops the robot)."""

    BINDINGS = [Binding("enter,q", "dismiss", "Close")]

    def __init__(self, image: Image.Image, namespace: str, drawing: str = "auto") -> None:
        super().__init__()
        self.picture = image
        self.namespace = namespace
        self.kind = image_class(drawing)

    def compose(self) -> ComposeResult:
        with Vertical(id="overview"):
            yield self.kind(id="overview-image")
            yield Static("F3, Enter or q closes", id="overview-caption")

    def on_mount(self) -> None:
        frame = self.query_one("#overview")
        frame.border_title = f"robot {self.namespace!r}, seen from the front left"
        columns, rows = fit_cells(
            self.picture.width, self.picture.height, self.size.width - 4, self.size.height - 4, cell_shape()
        )
        per_cell = pixels_per_cell(self.kind)
        image = self.query_one("#overview-image", self.kind)
        image.styles.width, image.styles.height = columns, rows
        image.image = self.picture.resize((columns * per_cell[0], rows * per_cell[1]), Image.Resampling.LANCZOS)
