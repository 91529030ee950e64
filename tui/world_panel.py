"""The world panel: every perceived object in a table, and the table seen from above or by the head camera."""

from __future__ import annotations

from rich.text import Text
from textual.app import ComposeResult
from textual.containers import Vertical
from textual.widget import Widget
from textual.widgets import DataTable

from tui.camera_view import CameraView
from tui.world import ARMS, WorldView, hex_color, object_rgb, reach_text, size_text

_TYPE_GLYPHS = {"cup": "c", "box": "b", "plate": "p", "bowl": "o"}


class ObjectTable(DataTable):
    """One row per perceived object: swatch, id, referring expression, type, size, reach."""

    def on_mount(self) -> None:
        # No cursor: a cursor row would paint over the colour swatches; the
        # referred object is marked with ▶ instead.
        self.cursor_type = "none"
        self.zebra_stripes = True
        self.add_column(" ", key="mark", width=2)
        self.add_column("", key="swatch", width=2)
        self.add_column("id", key="id")
        self.add_column("referring expression", key="name")
        self.add_column("type", key="type")
        self.add_column("size", key="size")
        self.add_column("reach", key="reach")

    def show(self, world: WorldView) -> None:
        self.clear()
        for object_id in sorted(world.objects, key=_id_order):
            obj = world.objects[object_id]
            marked = object_id == world.highlighted
            self.add_row(
                Text("▶" if marked else "", style="bold yellow"),
                Text("██", style=hex_color(object_rgb(obj))),
                Text(object_id, style="bold" if marked else ""),
                world.name_of(object_id) if object_id in world.descriptions else Text("…", style="dim"),
                obj.type,
                size_text(obj.size),
                reach_text(obj, world.reach.get(object_id)),
                key=object_id,
            )


def _holding(world: WorldView, arm: str) -> bool:
    """Whether the simulator reports ``arm``'s gripper holding something."""
    gripper = world.grippers.get(arm)
    return gripper is not None and bool(gripper.holding)


def _id_order(object_id: str) -> tuple[int, str]:
    """obj2 before obj10."""
    digits = "".join(c for c in object_id if c.isdigit())
    return (int(digits) if digits else 1 << 30, object_id)


class TableCanvas(Widget):
    """The table from above: robot at the bottom, its left on the left.

    Rows run along x (far at the top), columns along y (the robot's left on
    the screen's left, as a person standing behind the robot sees it).
    Objects are drawn as their footprint in their colour, grippers as R and L.
    """

    DEFAULT_X = (0.3, 1.0)
    DEFAULT_Y = (-0.55, 0.55)
    CELL_ASPECT = 2.0  # a terminal cell is about twice as tall as it is wide

    def __init__(self, **kwargs: object) -> None:
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.world = WorldView()

    def show(self, world: WorldView) -> None:
        self.world = world
        self.refresh()

    def on_resize(self) -> None:
        # the picture is scaled to the widget, so a new size needs a new drawing
        self.refresh()

    def _bounds(self) -> tuple[float, float, float, float]:
        xs = [*self.DEFAULT_X]
        ys = [*self.DEFAULT_Y]
        for obj in self.world.objects.values():
            position = obj.position
            xs.append(float(position[0]))
            ys.append(float(position[1]))
        for pose in self.world.ee.values():
            xs.append(float(pose[0]))
            ys.append(float(pose[1]))
        margin = 0.05
        return min(xs) - margin, max(xs) + margin, min(ys) - margin, max(ys) + margin

    def render(self) -> Text:
        width, height = self.size.width, max(1, self.size.height - 1)
        if width < 4:
            return Text("")
        x_min, x_max, y_min, y_max = self._bounds()
        # one scale for both axes so the picture is not distorted
        metres_per_col = max((y_max - y_min) / width, (x_max - x_min) / (height * self.CELL_ASPECT))
        metres_per_row = metres_per_col * self.CELL_ASPECT
        y_centre, x_centre = (y_max + y_min) / 2, (x_max + x_min) / 2

        def cell(x: float, y: float) -> tuple[int, int]:
            col = int((y_centre - y) / metres_per_col + width / 2)
            row = int((x_centre - x) / metres_per_row + height / 2)
            return row, col

        chars = [["·" if (r + c) % 4 == 0 and r % 2 == 0 else " " for c in range(width)] for r in range(height)]
        styles: list[list[str]] = [["grey35"] * width for _ in range(height)]

        def put(row: int, col: int, char: str, style: str) -> None:
            if 0 <= row < height and 0 <= col < width:
                chars[row][col] = char
                styles[row][col] = style

        for object_id, obj in self.world.objects.items():
            position, size = obj.position, obj.size
            colour = hex_color(object_rgb(obj))
            marked = object_id == self.world.highlighted
            style = f"bold black on {colour}" if marked else colour
            top, left = cell(position[0] + size[0] / 2, position[1] + size[1] / 2)
            bottom, right = cell(position[0] - size[0] / 2, position[1] - size[1] / 2)
            for row in range(top, max(top, bottom) + 1):
                for col in range(left, max(left, right) + 1):
                    put(row, col, "█" if not marked else " ", style)
            row, col = cell(position[0], position[1])
            put(row, col, _TYPE_GLYPHS.get(obj.type, "?"), f"bold black on {colour}")
            if marked:
                put(row, left - 1, "▶", "bold yellow")
                put(row, max(left, right) + 1, "◀", "bold yellow")
        for arm in ARMS:
            pose = self.world.ee.get(arm)
            if pose is None:
                continue
            row, col = cell(pose[0], pose[1])
            holding = _holding(self.world, arm)
            put(row, col, arm[0].upper(), "bold white on magenta" if holding else "bold white on dark_blue")

        text = Text()
        for row in range(height):
            for col in range(width):
                text.append(chars[row][col], styles[row][col])
            text.append("\n")
        text.append("↓ robot   R/L grippers", style="dim")
        return text


class WorldPanel(Vertical):
    """Objects table above the top-down picture, or above the head camera's picture."""

    def __init__(self, drawing: str = "auto", **kwargs: object) -> None:
        """``drawing`` is how the camera picture is drawn (see ``tui.camera_view.DRAWINGS``)."""
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.drawing = drawing
        self.view = "map"

    def compose(self) -> ComposeResult:
        yield ObjectTable(id="objects")
        yield TableCanvas(id="canvas")
        yield CameraView(self.drawing, id="camera")

    VIEWS = ("map", "camera", "close-up")  # what F2 steps through
    TITLES = {"map": "world", "camera": "world · head camera", "close-up": "world · head camera, close-up"}

    @property
    def camera_shown(self) -> bool:
        return bool(self.query_one(CameraView).display)

    @property
    def close_up(self) -> bool:
        return self.view == "close-up"

    def next_view(self) -> str:
        """Step to the next view (top-down map, camera, camera close-up) and show it."""
        self.show_view(self.VIEWS[(self.VIEWS.index(self.view) + 1) % len(self.VIEWS)])
        return self.view

    def show_view(self, view: str) -> None:
        """Show the top-down picture, or the camera's in place of it."""
        self.view = view
        self.border_title = self.TITLES[view]
        on = view != "map"
        self.query_one(CameraView).display = on
        self.query_one(TableCanvas).display = not on
        self.screen.set_class(on, "-camera")  # a short screen gives the picture the robot and action panels' rows

    def show(self, world: WorldView) -> None:
        self.query_one(ObjectTable).show(world)
        self.query_one(TableCanvas).show(world)
