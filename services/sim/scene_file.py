"""Scene files: a table's objects as data, checked on load, optionally re-placed at random.

Why data files: the paper's evaluation scenes, the demo scene and benchmark
variations are all the same few object kinds in different places, so a
scene is a short JSON document (format in docs/architecture.md) that anyone
can write without touching code. Every problem is reported with the file and
the field, never as a traceback.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from services.sim.layout import TABLE_TOP_Z
from shared.colours import COLOURS

SCENES_DIR = Path(__file__).resolve().parent / "scenes"
DEFAULT_SCENE = "default"

OBJECT_TYPES = ("cup", "box", "plate", "bowl")

DEFAULT_REGION = {"x": (0.45, 0.65), "y": (-0.18, 0.18)}  # reachable top-down by both arms


class SceneError(ValueError):
    """A scene that cannot be loaded; the message names the file and the problem."""


@dataclass(frozen=True)
class ObjectSpec:
    """One object: ``position`` is the centre of its bounding box (base frame)."""

    id: str
    type: str
    color: str
    rgb: tuple[float, float, float]
    size: tuple[float, float, float]
    mass: float
    position: tuple[float, float, float]
    yaw: float = 0.0
    friction: float = 0.8
    open_top: bool = False  # boxes only: a container with walls and a floor

    @property
    def footprint_radius(self) -> float:
        """Radius of the circle the object covers on the table."""
        if self.type in ("cup", "bowl", "plate"):
            return 0.5 * max(self.size[0], self.size[1])
        return 0.5 * math.hypot(self.size[0], self.size[1])


@dataclass(frozen=True)
class SceneSpec:
    name: str
    description: str
    objects: tuple[ObjectSpec, ...]
    region: dict[str, tuple[float, float]] = field(default_factory=lambda: dict(DEFAULT_REGION))
    gap: float = 0.03

    def object(self, object_id: str) -> ObjectSpec:
        for spec in self.objects:
            if spec.id == object_id:
                return spec
        raise SceneError(f"scene {self.name!r} has no object {object_id!r} (it has {', '.join(self.ids)})")

    @property
    def ids(self) -> list[str]:
        return [spec.id for spec in self.objects]


def available_scenes() -> list[str]:
    return sorted(path.stem for path in SCENES_DIR.glob("*.json"))


def scene_path(name_or_path: str) -> Path:
    """A scene name (``task1_stack_cups``) or a path to a JSON file."""
    path = Path(name_or_path)
    if path.suffix == ".json" or path.parent != Path("."):
        if not path.is_file():
            raise SceneError(f"scene file {name_or_path} does not exist")
        return path
    candidate = SCENES_DIR / f"{name_or_path}.json"
    if not candidate.is_file():
        raise SceneError(f"unknown scene {name_or_path!r}; known scenes: {', '.join(available_scenes())}")
    return candidate


def load_scene(name_or_path: str) -> SceneSpec:
    path = scene_path(name_or_path)
    try:
        document = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise SceneError(f"cannot read scene {path}: {exc}") from exc
    return parse_scene(document, source=str(path), default_name=path.stem)


def parse_scene(document: Any, source: str = "scene", default_name: str = "scene") -> SceneSpec:
    if not isinstance(document, dict) or not isinstance(document.get("objects"), list):
        raise SceneError(f"{source}: a scene is a JSON object with an 'objects' list")
    objects = tuple(_parse_object(item, index, source) for index, item in enumerate(document["objects"]))
    ids = [spec.id for spec in objects]
    if len(set(ids)) != len(ids):
        raise SceneError(f"{source}: object ids must be unique, got {ids}")
    region = dict(DEFAULT_REGION)
    placement = document.get("random", {})
    if not isinstance(placement, dict):
        raise SceneError(f"{source}: 'random' must be an object with 'x', 'y' ranges")
    for axis in ("x", "y"):
        if axis in placement:
            low, high = _numbers(placement[axis], 2, f"{source}: random.{axis}")
            if low >= high:
                raise SceneError(f"{source}: random.{axis} must be [low, high] with low < high")
            region[axis] = (low, high)
    gap = float(placement.get("gap", 0.03))
    return SceneSpec(
        str(document.get("name", default_name)), str(document.get("description", "")), objects, region, gap
    )


def _triple(numbers: list[float]) -> tuple[float, float, float]:
    """Three numbers already checked by :func:`_numbers`, as the fixed-length tuple a spec holds."""
    return numbers[0], numbers[1], numbers[2]


def _numbers(value: Any, count: int | tuple[int, ...], where: str) -> list[float]:
    counts = (count,) if isinstance(count, int) else count
    if not isinstance(value, (list, tuple)) or len(value) not in counts:
        raise SceneError(f"{where} must be a list of {' or '.join(map(str, counts))} numbers")
    try:
        numbers = [float(v) for v in value]
    except (TypeError, ValueError) as exc:
        raise SceneError(f"{where} must hold numbers") from exc
    if not all(math.isfinite(v) for v in numbers):
        raise SceneError(f"{where} must hold finite numbers")
    return numbers


def _parse_object(item: Any, index: int, source: str) -> ObjectSpec:
    where = f"{source}: objects[{index}]"
    if not isinstance(item, dict):
        raise SceneError(f"{where} must be an object")
    object_id = item.get("id", f"obj{index}")
    kind = item.get("type")
    if kind not in OBJECT_TYPES:
        raise SceneError(f"{where}: type must be one of {', '.join(OBJECT_TYPES)}, got {kind!r}")
    color = item.get("color")
    if color not in COLOURS:
        raise SceneError(f"{where}: color must be one of {', '.join(COLOURS)}, got {color!r}")
    rgb = _triple(_numbers(item["rgb"], 3, f"{where}.rgb")) if "rgb" in item else COLOURS[color]
    size = _triple(_numbers(item.get("size"), 3, f"{where}.size"))
    if min(size) <= 0.0 or max(size) > 1.0:
        raise SceneError(f"{where}: size must be between 0 and 1 m per axis, got {list(size)}")
    mass = float(item.get("mass", 0.1))
    if not 0.0 < mass <= 20.0:
        raise SceneError(f"{where}: mass must be in (0, 20] kg, got {mass}")
    xyz = _numbers(item.get("position"), (2, 3), f"{where}.position")
    if len(xyz) == 2:
        xyz.append(TABLE_TOP_Z + size[2] / 2)
    friction = float(item.get("friction", 0.8))
    if not 0.0 <= friction <= 3.0:
        raise SceneError(f"{where}: friction must be in [0, 3], got {friction}")
    return ObjectSpec(
        str(object_id),
        kind,
        color,
        rgb,
        size,
        mass,
        _triple(xyz),
        float(item.get("yaw", 0.0)),
        friction,
        bool(item.get("open_top", False)),
    )


def with_positions(scene: SceneSpec, positions: dict[str, Any]) -> SceneSpec:
    """The scene with some objects moved (``{id: [x, y]}`` rests on the table, ``[x, y, z]`` is exact)."""
    moved = {}
    for object_id, value in positions.items():
        spec = scene.object(object_id)
        xyz = _numbers(value, (2, 3), f"poses.{object_id}")
        if len(xyz) == 2:
            xyz.append(TABLE_TOP_Z + spec.size[2] / 2)
        moved[object_id] = _triple(xyz)
    return replace(scene, objects=tuple(replace(s, position=moved.get(s.id, s.position)) for s in scene.objects))


def randomized(scene: SceneSpec, seed: int, attempts: int = 2000) -> SceneSpec:
    """Every object re-placed at random in the scene's region, none overlapping (same seed, same scene).

    Objects that start on top of another one (stacked) keep their place: only
    objects resting on the table are shuffled.
    """
    rng = np.random.default_rng(seed)
    placed: list[tuple[float, float, float]] = []  # x, y, radius
    moved: dict[str, tuple[float, float, float]] = {}
    on_table = [s for s in scene.objects if abs(s.position[2] - (TABLE_TOP_Z + s.size[2] / 2)) < 0.01]
    for spec in sorted(on_table, key=lambda s: -s.footprint_radius):
        radius = spec.footprint_radius
        (x0, x1), (y0, y1) = scene.region["x"], scene.region["y"]
        for _ in range(attempts):
            x, y = rng.uniform(x0, x1), rng.uniform(y0, y1)
            if all(math.hypot(x - px, y - py) >= radius + pr + scene.gap for px, py, pr in placed):
                placed.append((x, y, radius))
                moved[spec.id] = (float(x), float(y), spec.position[2])
                break
        else:
            raise SceneError(f"cannot place {spec.id} in the region {scene.region} without overlap")
    return replace(scene, objects=tuple(replace(s, position=moved.get(s.id, s.position)) for s in scene.objects))
