"""The head camera's picture with what the robot perceives drawn on it (pure: no widgets, no bus).

Runs on a worker thread: decoding the frame, fitting the camera model,
scaling and drawing take tens of milliseconds, which the UI thread must not
spend while a person types.

The camera model comes from the frame itself. ``sim/cloud`` is organised: the
point behind pixel (u, v) is ``xyz[v, u]`` in the base frame, and
``camera_pose`` says where the camera was. A pinhole camera maps a point at
``(x, y, z)`` in the camera link's frame (x forward, y left, z up) to
``u = cx - fx * y / x``, ``v = cy - fz * z / x``, so two least-squares fits on
a sample of pixels give the intrinsics of whatever camera published the
frame, at whatever resolution, without a copy of the simulator's numbers.
"""

from __future__ import annotations

import io
from dataclasses import dataclass, field

import numpy as np
from PIL import Image, ImageDraw
from rich.console import Console
from scipy.spatial.transform import Rotation
from textual.strip import Strip
from textual_image.renderable.halfcell import Image as HalfBlocks

from shared.messages import Cloud, PerceivedObject
from tui.world import ARMS, WorldView, hex_color, object_rgb

SAMPLE_PIXELS = 600  # pixels used to fit the intrinsics (plenty for two unknowns per axis)
NEAREST = 0.05  # m in front of the camera: anything nearer is not drawn
OUTLINE = (255, 255, 255)
HIGHLIGHT = (255, 215, 0)
GRIPPER = {False: (0, 200, 255), True: (255, 0, 255)}  # empty hand, holding something


@dataclass(frozen=True)
class Pinhole:
    """Where the camera is (base frame) and how it maps directions to pixels of its own picture."""

    rotation: np.ndarray  # (3, 3) camera link axes in the base frame
    origin: np.ndarray  # (3,)
    fx: float
    cx: float
    fy: float
    cy: float

    def project(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pixel coordinates (N, 2) of base-frame points (N, 3), and which lie in front of the camera."""
        local = (np.asarray(points, float) - self.origin) @ self.rotation
        ahead = local[:, 0] > NEAREST
        depth = np.where(ahead, local[:, 0], 1.0)
        uv = np.stack([self.cx - self.fx * local[:, 1] / depth, self.cy - self.fy * local[:, 2] / depth], axis=1)
        return uv, ahead


def fit_pinhole(xyz: np.ndarray, camera_pose: list[float]) -> Pinhole | None:
    """The camera model of an organised cloud, or None when too few pixels have a point."""
    rotation = Rotation.from_quat([camera_pose[4], camera_pose[5], camera_pose[6], camera_pose[3]]).as_matrix()
    origin = np.asarray(camera_pose[:3], float)
    rows, cols = np.nonzero(np.isfinite(xyz[..., 0]))
    if len(rows) < 10:
        return None
    pick = np.linspace(0, len(rows) - 1, min(SAMPLE_PIXELS, len(rows))).astype(int)
    rows, cols = rows[pick], cols[pick]
    local = (xyz[rows, cols].astype(float) - origin) @ rotation
    ahead = local[:, 0] > NEAREST
    if ahead.sum() < 10:
        return None
    local, rows, cols = local[ahead], rows[ahead], cols[ahead]
    across, up = -local[:, 1] / local[:, 0], -local[:, 2] / local[:, 0]
    (fx, cx), *_ = np.linalg.lstsq(np.stack([across, np.ones_like(across)], 1), cols + 0.5, rcond=None)
    (fy, cy), *_ = np.linalg.lstsq(np.stack([up, np.ones_like(up)], 1), rows + 0.5, rcond=None)
    return Pinhole(rotation, origin, float(fx), float(cx), float(fy), float(cy))


@dataclass(frozen=True)
class Label:
    """Text to show over the picture at a cell (column, row) of the drawn image."""

    column: int
    row: int
    text: str
    style: str


@dataclass
class Picture:
    """A frame ready for the screen: the image at its final size and the labels to put over it."""

    image: Image.Image
    columns: int
    rows: int
    labels: list[Label] = field(default_factory=list)
    stamp: float = 0.0
    lines: list[Strip] | None = None  # the picture already drawn in half-blocks, one strip per row


def half_block_lines(image: Image.Image, columns: int, rows: int) -> list[Strip]:
    """Draw ``image`` as coloured half-blocks with textual-image, here rather than on the UI thread.

    Drawing is a style per cell: about 10 ms for a 53 × 20 picture and 70 ms
    for 120 × 45, which at several frames a second would make typing lag if
    the screen did it.
    """
    console = Console(width=columns, height=rows, color_system="truecolor", file=io.StringIO(), legacy_windows=False)
    options = console.options.update(width=columns, height=rows)
    return [Strip(line, columns) for line in console.render_lines(HalfBlocks(image, columns, rows), options, pad=False)]


def fit_cells(width: int, height: int, columns: int, rows: int, cell: tuple[int, int]) -> tuple[int, int]:
    """The largest (columns, rows) that show a ``width`` × ``height`` picture undistorted in the space given.

    ``cell`` is a terminal cell's size in pixels (width, height).
    """
    cell_w, cell_h = cell
    fitted_columns = min(columns, int(rows * cell_h / cell_w * width / height))
    fitted_rows = min(rows, max(1, round(fitted_columns * cell_w / cell_h * height / width)))
    return max(1, fitted_columns), fitted_rows


def compose(
    cloud: Cloud,
    world: WorldView,
    columns: int,
    rows: int,
    cell: tuple[int, int],
    pixels_per_cell: tuple[int, int],
    close_up: bool = False,
) -> Picture:
    """The camera frame scaled to fit ``columns`` × ``rows`` cells, objects outlined, grippers marked.

    ``pixels_per_cell`` is how many image pixels one cell shows ((1, 2) for
    coloured half-blocks, which are then drawn here too; the cell's pixel
    size for a graphics protocol, which the terminal draws). ``close_up``
    shows only the part of the frame around the perceived objects: in a
    terminal-sized picture of the whole frame a cup is two cells wide.
    """
    picture = _marked(cloud, world, columns, rows, cell, pixels_per_cell, close_up)
    if pixels_per_cell == (1, 2):
        picture.lines = half_block_lines(picture.image, picture.columns, picture.rows)
    return picture


def _marked(
    cloud: Cloud,
    world: WorldView,
    columns: int,
    rows: int,
    cell: tuple[int, int],
    pixels_per_cell: tuple[int, int],
    close_up: bool,
) -> Picture:
    """The scaled frame with outlines and gripper marks drawn in, and the labels to lay over it."""
    rgb = np.asarray(cloud.rgb, dtype=np.uint8)
    height, width = rgb.shape[:2]
    frame = Image.fromarray(rgb, "RGB")
    camera = fit_pinhole(np.asarray(cloud.xyz), list(cloud.camera_pose))
    region = _region(camera, world, width, height) if close_up and camera is not None else (0, 0, width, height)
    columns, rows = fit_cells(region[2] - region[0], region[3] - region[1], columns, rows, cell)
    size = (columns * pixels_per_cell[0], rows * pixels_per_cell[1])
    image = frame.resize(size, Image.Resampling.BILINEAR, box=region)
    picture = Picture(image, columns, rows, stamp=cloud.stamp)
    if camera is None:
        return picture
    offset = np.array(region[:2], float)
    scale = np.array([size[0] / (region[2] - region[0]), size[1] / (region[3] - region[1])])
    to_cell = np.array([columns / size[0], rows / size[1]])
    draw = ImageDraw.Draw(image)
    thickness = max(1, pixels_per_cell[1] // 2)
    places = Placer(columns, rows)
    # the object the user just named is labelled first, so it gets the place nearest its outline
    for object_id, obj in sorted(world.objects.items(), key=lambda item: item[0] != world.highlighted):
        box = _outline(camera, obj, offset, scale, size)
        if box is None:
            continue
        marked = object_id == world.highlighted
        draw.rectangle(box, outline=HIGHLIGHT if marked else OUTLINE, width=thickness)
        column, top, _right, bottom = (np.array(box, float) * np.tile(to_cell, 2)).astype(int)
        name = world.descriptions.get(object_id) or f"a {obj.color} {obj.type}"
        style = f"bold black on {hex_color(HIGHLIGHT)}" if marked else f"black on {hex_color(object_rgb(obj))}"
        column, row = places.take(
            int(column),
            [int(top) - 1, int(bottom) + 1, int(top) - 2, int(bottom) + 2, int(top), int(bottom)],
            len(name),
        )
        picture.labels.append(Label(column, row, name, style))
    for arm in ARMS:
        pose = world.ee.get(arm)
        if pose is None:
            continue
        uv, ahead = camera.project(np.asarray([pose[:3]], float))
        point = (uv[0] - offset) * scale
        if not ahead[0] or not (0 <= point[0] < size[0] and 0 <= point[1] < size[1]):
            continue
        gripper = world.grippers.get(arm)
        holding = gripper is not None and bool(gripper.holding)
        colour = GRIPPER[holding]
        radius = max(2, 2 * pixels_per_cell[0])
        draw.ellipse(
            [point[0] - radius, point[1] - radius, point[0] + radius, point[1] + radius],
            outline=colour,
            width=thickness,
        )
        column, row = (point * to_cell).astype(int)
        column, row = places.take(int(column) + 1, [int(row), int(row) - 1, int(row) + 1], 1)
        picture.labels.append(Label(column, row, arm[0].upper(), f"bold white on {hex_color(colour)}"))
    return picture


class Placer:
    """Keeps labels from covering each other: each takes the first of its preferred rows where it fits."""

    def __init__(self, columns: int, rows: int) -> None:
        self.columns, self.rows = columns, rows
        self.taken: dict[int, list[tuple[int, int]]] = {}

    def take(self, column: int, rows: list[int], width: int) -> tuple[int, int]:
        """(column, row) for a label ``width`` cells wide; the first preferred row if all are taken."""
        column = max(0, min(column, self.columns - width))
        span = (column, column + width)
        inside = [r for r in rows if 0 <= r < self.rows] or [max(0, min(rows[0], self.rows - 1))]
        free = [r for r in inside if all(span[1] <= a or b <= span[0] for a, b in self.taken.get(r, []))]
        row = (free or inside)[0]
        self.taken.setdefault(row, []).append(span)
        return column, row


def _corners(camera: Pinhole, obj: PerceivedObject) -> np.ndarray | None:
    """Frame pixels (8, 2) of the corners of the object's bounding box, None when it is not in front."""
    half = np.asarray(obj.size, float) / 2
    corners = np.asarray(obj.position, float) + half * np.array(
        [[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
    )
    uv, ahead = camera.project(corners)
    return uv if ahead.all() else None


def _region(camera: Pinhole, world: WorldView, width: int, height: int) -> tuple[int, int, int, int]:
    """The part of the frame (left, top, right, bottom) around every object seen, in the frame's shape.

    The objects' extent plus as much again around it, at least a third of
    the frame across; the whole frame when no object is in view.
    """
    seen = [uv for uv in (_corners(camera, obj) for obj in world.objects.values()) if uv is not None]
    if not seen:
        return 0, 0, width, height
    points = np.clip(np.concatenate(seen), 0, [width, height])
    centre = (points.min(axis=0) + points.max(axis=0)) / 2
    span = np.ptp(points, axis=0)
    across = min(width, max(2 * span[0], 2 * span[1] * width / height, width / 3))
    half_w, half_h = across / 2, across / 2 * height / width
    left = float(np.clip(centre[0] - half_w, 0, width - 2 * half_w))
    top = float(np.clip(centre[1] - half_h, 0, height - 2 * half_h))
    return int(left), int(top), int(round(left + 2 * half_w)), int(round(top + 2 * half_h))


def _outline(
    camera: Pinhole, obj: PerceivedObject, offset: np.ndarray, scale: np.ndarray, size: tuple[int, int]
) -> tuple[int, int, int, int] | None:
    """The object's bounding box as a pixel rectangle of the scaled image, or None when it is out of view."""
    uv = _corners(camera, obj)
    if uv is None:
        return None
    uv = (uv - offset) * scale
    left, top = np.clip(uv.min(axis=0), 0, [size[0] - 1, size[1] - 1])
    right, bottom = np.clip(uv.max(axis=0), 0, [size[0] - 1, size[1] - 1])
    if right - left < 1 or bottom - top < 1:
        return None
    return int(left), int(top), int(right), int(bottom)
