"""Synthetic organised point clouds: a pinhole camera ray-cast onto a tabletop.

Why it exists: the perception library must be testable and benchmarkable on
its own, with exact ground truth and full control over the awkward cases
(objects 1 cm apart, an arm sweeping over the table, sensor noise, missing
returns). Shapes are analytic — boxes, solid and hollow cylinders, capsules —
so every pixel's hit point is exact before optional noise is added.

Frames follow the project's conventions: robot base frame, x forward, y left,
z up, metres; the camera's optical axis is its local +z.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import msgspec
import numpy as np
from scipy.spatial.transform import Rotation

from services.perception.robot_mask import segments_from_state
from shared.colours import rgb8
from shared.messages import Cloud, SimState, typed
from shared.robot import ROBOT
from shared.robot.pr2 import TOOL_OFFSET

RGB = tuple[int, int, int]

TABLE_RGB: RGB = (150, 110, 70)
FLOOR_RGB: RGB = (90, 90, 95)
ARM_RGB: RGB = (210, 210, 215)


@dataclass(frozen=True)
class Box:
    """A box resting on (or above) the table, rotated by ``yaw`` about z."""

    center: tuple[float, float, float]
    size: tuple[float, float, float]
    colour: str
    yaw: float = 0.0
    kind: str = "box"


@dataclass(frozen=True)
class Cylinder:
    """A vertical cylinder; ``wall`` > 0 makes it an open vessel (cup, bowl)."""

    center: tuple[float, float, float]
    radius: float
    height: float
    colour: str
    wall: float = 0.0
    kind: str = "cup"


@dataclass(frozen=True)
class Capsule:
    """A robot link: the set of points within ``radius`` of segment a–b."""

    a: tuple[float, float, float]
    b: tuple[float, float, float]
    radius: float


Shape = Box | Cylinder


@dataclass
class Scene:
    """A table (a slab top at ``table_height``), objects on it, arm links above it."""

    objects: list[Shape]
    table_height: float = 0.75
    table_x: tuple[float, float] = (0.45, 1.25)
    table_y: tuple[float, float] = (-0.75, 0.75)
    links: list[Capsule] = field(default_factory=list)

    def truth(self) -> list[dict]:
        """Ground truth in the world-state convention: axis-aligned box centre and extent."""
        items = []
        for index, shape in enumerate(self.objects):
            lo, hi = _aabb(shape)
            items.append(
                {
                    "id": f"truth{index}",
                    "color": shape.colour,
                    "type": shape.kind,
                    "position": ((lo + hi) / 2).tolist(),
                    "size": (hi - lo).tolist(),
                }
            )
        return items


def _aabb(shape: Shape) -> tuple[np.ndarray, np.ndarray]:
    c = np.asarray(shape.center, float)
    if isinstance(shape, Cylinder):
        half = np.array([shape.radius, shape.radius, shape.height / 2])
    else:
        cos, sin = abs(np.cos(shape.yaw)), abs(np.sin(shape.yaw))
        sx, sy, sz = shape.size
        half = np.array([(sx * cos + sy * sin) / 2, (sx * sin + sy * cos) / 2, sz / 2])
    return c - half, c + half


@dataclass(frozen=True)
class Camera:
    """A pinhole camera at ``position`` looking at ``target`` (no roll)."""

    position: tuple[float, float, float] = (0.05, 0.0, 1.47)
    target: tuple[float, float, float] = (0.85, 0.0, 0.75)
    width: int = 640
    height: int = 480

    def rotation(self) -> np.ndarray:
        """Columns: the optical x (right), y (down), z (forward) axes in the base frame."""
        forward = np.subtract(self.target, self.position).astype(float)
        forward /= np.linalg.norm(forward)
        right = np.cross(forward, [0.0, 0.0, 1.0])
        right /= np.linalg.norm(right)
        down = np.cross(forward, right)
        return np.stack([right, down, forward], axis=1)

    def pose(self) -> list[float]:
        """``[x, y, z, qw, qx, qy, qz]`` of the optical frame."""
        from scipy.spatial.transform import Rotation

        qx, qy, qz, qw = Rotation.from_matrix(self.rotation()).as_quat()
        return [*map(float, self.position), float(qw), float(qx), float(qy), float(qz)]

    def rays(self) -> np.ndarray:
        """Unit ray directions (H, W, 3) in the base frame."""
        f = ROBOT.camera.intrinsics(self.width, self.height)[0]  # the robot's head camera at this size
        u, v = np.meshgrid(np.arange(self.width) + 0.5, np.arange(self.height) + 0.5)
        local = np.stack([(u - self.width / 2) / f, (v - self.height / 2) / f, np.ones_like(u)], axis=-1)
        directions = local @ self.rotation().T
        return directions / np.linalg.norm(directions, axis=-1, keepdims=True)


def render(
    scene: Scene, camera: Camera = Camera(), *, noise: float = 0.0, dropout: float = 0.0, seed: int = 0
) -> Cloud:
    """Ray-cast ``scene`` into a ``sim/cloud`` message as perception's subscription hands it over (see :func:`render_map`)."""
    cloud = typed("cloud", render_map(scene, camera, noise=noise, dropout=dropout, seed=seed))
    assert isinstance(cloud, Cloud)
    return cloud


def render_map(
    scene: Scene, camera: Camera = Camera(), *, noise: float = 0.0, dropout: float = 0.0, seed: int = 0
) -> dict:
    """Ray-cast ``scene`` and return the ``sim/cloud`` map a simulator would publish.

    ``noise`` is the standard deviation of range noise in metres, ``dropout``
    the fraction of pixels with no return (NaN), both seeded.
    """
    origin = np.asarray(camera.position, float)
    rays = camera.rays().reshape(-1, 3)
    n = len(rays)
    best = np.full(n, np.inf)
    colour = np.zeros((n, 3))
    normal = np.zeros((n, 3))

    def take(t: np.ndarray, rgb: RGB, normals: np.ndarray) -> None:
        closer = t < best
        best[closer] = t[closer]
        colour[closer] = rgb
        normal[closer] = normals[closer] if normals.ndim == 2 else normals

    up = np.array([0.0, 0.0, 1.0])
    take(_hit_plane(origin, rays, 0.0, None, None), FLOOR_RGB, up)
    take(_hit_plane(origin, rays, scene.table_height, scene.table_x, scene.table_y), TABLE_RGB, up)
    for shape in scene.objects:
        rgb = rgb8(shape.colour)
        if isinstance(shape, Box):
            t, normals = _hit_box(origin, rays, shape)
        else:
            t, normals = _hit_cylinder(origin, rays, shape)
        take(t, rgb, normals)
    for link in scene.links:
        t, normals = _hit_capsule(origin, rays, link)
        take(t, ARM_RGB, normals)

    rng = np.random.default_rng(seed)
    hit = np.isfinite(best) & (best < 4.5)
    if noise > 0:
        best = best + rng.normal(0.0, noise, n)
    if dropout > 0:
        hit &= rng.random(n) >= dropout
    xyz = origin + rays * best[:, None]
    xyz[~hit] = np.nan
    light = np.array([-0.3, 0.2, 1.0]) / np.linalg.norm([-0.3, 0.2, 1.0])
    shade = 0.45 + 0.55 * np.clip(np.abs(normal @ light), 0.0, 1.0)
    rgb = np.clip(colour * shade[:, None], 0, 255)
    rgb[~hit] = 0
    image_shape = (camera.height, camera.width, 3)
    return {
        "stamp": 0.0,
        "xyz": xyz.reshape(image_shape).astype(np.float32),
        "rgb": rgb.reshape(image_shape).astype(np.uint8),
        "camera_pose": camera.pose(),
        "width": camera.width,
        "height": camera.height,
    }


def _hit_plane(
    origin: np.ndarray, rays: np.ndarray, z: float, xs: tuple[float, float] | None, ys: tuple[float, float] | None
) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (z - origin[2]) / rays[:, 2]
    t = np.where(t > 1e-6, t, np.inf)
    if xs is not None and ys is not None:
        p = origin + rays * np.where(np.isfinite(t), t, 0.0)[:, None]
        inside = (p[:, 0] >= xs[0]) & (p[:, 0] <= xs[1]) & (p[:, 1] >= ys[0]) & (p[:, 1] <= ys[1])
        t = np.where(inside, t, np.inf)
    return t


def _hit_box(origin: np.ndarray, rays: np.ndarray, box: Box) -> tuple[np.ndarray, np.ndarray]:
    """Slab test in the box frame; returns entry distances and outward normals."""
    cos, sin = np.cos(box.yaw), np.sin(box.yaw)
    rot = np.array([[cos, -sin, 0.0], [sin, cos, 0.0], [0.0, 0.0, 1.0]])
    o = (origin - np.asarray(box.center)) @ rot
    d = rays @ rot
    half = np.asarray(box.size) / 2
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = (-half - o) / d
        t2 = (half - o) / d
    t_near = np.minimum(t1, t2)
    t_far = np.maximum(t1, t2)
    t_near = np.where(np.isnan(t_near), -np.inf, t_near)
    t_far = np.where(np.isnan(t_far), np.inf, t_far)
    entry = t_near.max(axis=1)
    exit_ = t_far.min(axis=1)
    t = np.where((entry <= exit_) & (entry > 1e-6), entry, np.inf)
    axis = t_near.argmax(axis=1)
    local = np.zeros_like(d)
    local[np.arange(len(d)), axis] = -np.sign(d[np.arange(len(d)), axis])
    return t, local @ rot.T


def _hit_cylinder(origin: np.ndarray, rays: np.ndarray, cyl: Cylinder) -> tuple[np.ndarray, np.ndarray]:
    """Outer wall, top (disc or rim), and for vessels the inner wall and floor."""
    c = np.asarray(cyl.center, float)
    bottom, top = c[2] - cyl.height / 2, c[2] + cyl.height / 2
    o = origin - c
    n = len(rays)
    best = np.full(n, np.inf)
    normals = np.zeros((n, 3))

    def consider(t: np.ndarray, nrm: np.ndarray) -> None:
        closer = (t > 1e-6) & (t < best)
        best[closer] = t[closer]
        normals[closer] = nrm[closer] if nrm.ndim == 2 else nrm

    def wall(radius: float, lo: float, hi: float, far: bool) -> None:
        a = rays[:, 0] ** 2 + rays[:, 1] ** 2
        b = 2 * (o[0] * rays[:, 0] + o[1] * rays[:, 1])
        k = o[0] ** 2 + o[1] ** 2 - radius**2
        disc = b * b - 4 * a * k
        with np.errstate(invalid="ignore", divide="ignore"):
            root = np.sqrt(np.where(disc >= 0, disc, np.nan))
            t = (-b + root) / (2 * a) if far else (-b - root) / (2 * a)
        z = origin[2] + rays[:, 2] * t
        t = np.where((disc >= 0) & (z >= lo) & (z <= hi), t, np.inf)
        p = o + rays * np.where(np.isfinite(t), t, 0.0)[:, None]
        nrm = np.stack([p[:, 0], p[:, 1], np.zeros(n)], axis=1) / radius
        consider(t, -nrm if far else nrm)

    def cap(z: float, r_in: float, r_out: float) -> None:
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (z - origin[2]) / rays[:, 2]
        p = o + rays * np.where(np.isfinite(t), t, 0.0)[:, None]
        r = np.hypot(p[:, 0], p[:, 1])
        consider(np.where((r >= r_in) & (r <= r_out), t, np.inf), np.array([0.0, 0.0, 1.0]))

    wall(cyl.radius, bottom, top, far=False)
    if cyl.wall > 0:
        inner = cyl.radius - cyl.wall
        floor = bottom + cyl.wall
        cap(top, inner, cyl.radius)
        wall(inner, floor, top, far=True)
        cap(floor, 0.0, inner)
    else:
        cap(top, 0.0, cyl.radius)
    return best, normals


def _hit_capsule(origin: np.ndarray, rays: np.ndarray, cap: Capsule) -> tuple[np.ndarray, np.ndarray]:
    """A capsule approximated by overlapping spheres along its axis (enough for masking tests)."""
    a, b = np.asarray(cap.a, float), np.asarray(cap.b, float)
    count = max(2, int(np.ceil(np.linalg.norm(b - a) / (cap.radius * 0.5))) + 1)
    best = np.full(len(rays), np.inf)
    normals = np.zeros_like(rays)
    for s in np.linspace(0.0, 1.0, count):
        centre = a + (b - a) * s
        oc = origin - centre
        half_b = rays @ oc
        disc = half_b**2 - (oc @ oc - cap.radius**2)
        with np.errstate(invalid="ignore"):
            t = -half_b - np.sqrt(np.where(disc >= 0, disc, np.nan))
        t = np.where((disc >= 0) & (t > 1e-6), t, np.inf)
        closer = t < best
        best[closer] = t[closer]
        normals[closer] = (origin + rays[closer] * t[closer, None] - centre) / cap.radius
    return best, normals


SHOULDER = {"right": (-0.05, -0.188, 1.121), "left": (-0.05, 0.188, 1.121)}
POINTING_DOWN = (0.7071068, 0.0, 0.7071068, 0.0)  # tool x axis along -z
UPPER_ARM, FOREARM = 0.4, 0.321  # shoulder lift -> elbow -> wrist flex (m)
SHOULDER_LIFT_OFFSET = 0.1


def _frame(x_axis: np.ndarray, origin: np.ndarray) -> list[float]:
    """A pose whose x axis points along ``x_axis`` and whose y axis stays level."""
    x = x_axis / np.linalg.norm(x_axis)
    y = np.cross([0.0, 0.0, 1.0], x)
    y = y / np.linalg.norm(y) if np.linalg.norm(y) > 1e-6 else np.array([0.0, 1.0, 0.0])
    qx, qy, qz, qw = Rotation.from_matrix(np.column_stack([x, y, np.cross(x, y)])).as_quat()
    return [*map(float, origin), float(qw), float(qx), float(qy), float(qz)]


def reaching_arm(
    tool: tuple[float, float, float], arm: str = "right", holding: bool = False
) -> tuple[list[Capsule], SimState]:
    """A PR2 arm, with the project model's link lengths, its gripper pointing down at ``tool``.

    Returns the capsules to render (the model's link shapes, from the same
    poses) and the matching ``sim/state`` (its ``links``, ``ee`` and
    ``grippers``), so masking is exercised exactly as with the simulator's state.
    """
    side = "r" if arm == "right" else "l"
    lift = np.asarray(SHOULDER[arm]) + np.array([SHOULDER_LIFT_OFFSET, 0.0, 0.0])
    tool_p = np.asarray(tool, float)
    wrist = tool_p + np.array([0.0, 0.0, TOOL_OFFSET])
    reach = wrist - lift
    distance = float(np.linalg.norm(reach))
    along = (distance**2 + UPPER_ARM**2 - FOREARM**2) / (2 * distance)
    up = np.cross(np.cross(reach, [0.0, 0.0, 1.0]), reach)
    up = up / np.linalg.norm(up) if np.linalg.norm(up) > 1e-9 else np.array([0.0, 0.0, 1.0])
    if up[2] < 0:
        up = -up
    elbow = lift + reach / distance * along + up * np.sqrt(max(UPPER_ARM**2 - along**2, 0.0))
    down = np.array([0.0, 0.0, -1.0])
    width = 0.07 if holding else 0.08
    palm = _frame(down, wrist)
    palm_y = Rotation.from_quat([*palm[4:], palm[3]]).as_matrix()[:, 1]
    links = {
        f"{side}_shoulder_pan_link": _frame(np.array([1.0, 0.0, 0.0]), np.asarray(SHOULDER[arm])),
        f"{side}_shoulder_lift_link": _frame(elbow - lift, lift),
        f"{side}_upper_arm_link": _frame(elbow - lift, lift),
        f"{side}_elbow_flex_link": _frame(wrist - elbow, elbow),
        f"{side}_forearm_link": _frame(wrist - elbow, elbow),
        f"{side}_wrist_flex_link": palm,
        f"{side}_gripper_palm_link": palm,
        f"{side}_gripper_l_finger_link": [*(wrist + palm_y * width / 2), *palm[3:]],
        f"{side}_gripper_r_finger_link": [*(wrist - palm_y * width / 2), *palm[3:]],
        f"{side}_gripper_tool_frame": [*tool_p, *palm[3:]],
    }
    fields = {
        "stamp": 0.0,
        "joints": {},
        "links": {name: [float(v) for v in pose] for name, pose in links.items()},
        "ee": {arm: [*map(float, tool_p), *POINTING_DOWN]},
        "grippers": {arm: {"width": width, "effort": ROBOT.gripper.default_effort if holding else 0.0}},
    }
    state = msgspec.convert(fields, SimState)
    capsules = [Capsule(tuple(s.a), tuple(s.b), s.radius) for s in segments_from_state(state, margin=0.0)]
    return capsules, state
