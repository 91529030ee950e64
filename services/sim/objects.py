"""Build the table and the scene objects as SAPIEN rigid bodies made of convex pieces.

Why pieces: cups, bowls and container boxes are open at the top so another
object can sit in them, and PhysX needs convex shapes for moving bodies; a
ring of thin wall panels around a floor gives exactly that. Each object's
origin is the centre of its bounding box, so its pose is its ``position``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import sapien
from scipy.spatial.transform import Rotation

from services.sim.layout import TABLE_THICKNESS, TABLE_TOP_Z, TABLE_X, TABLE_Y
from services.sim.scene_file import ObjectSpec

WALL = 0.006  # wall thickness of cups, bowls and containers
FLOOR = 0.008  # floor thickness
PANELS = 16  # wall panels around a round object
TABLE_RGB = (0.62, 0.58, 0.54)
TABLE_FRICTION = 0.5


@dataclass(frozen=True)
class Piece:
    """A box (``half`` sizes) or an upright cylinder (``half`` = radius, radius, half height)."""

    kind: str
    half: tuple[float, float, float]
    pose: sapien.Pose

    @property
    def volume(self) -> float:
        if self.kind == "box":
            return 8.0 * self.half[0] * self.half[1] * self.half[2]
        return math.pi * self.half[0] ** 2 * 2.0 * self.half[2]


_UPRIGHT = Rotation.from_euler("y", 90, degrees=True)  # SAPIEN cylinders lie along x


def _quat_wxyz(rotation: Rotation) -> list[float]:
    x, y, z, w = rotation.as_quat()
    return [w, x, y, z]


def _cylinder(radius: float, half_height: float, z: float) -> Piece:
    return Piece("cylinder", (radius, radius, half_height), sapien.Pose([0, 0, z], _quat_wxyz(_UPRIGHT)))


def _ring(radius_bottom: float, radius_top: float, z0: float, z1: float) -> list[Piece]:
    """Wall panels from height z0 to z1, leaning out when the top radius is larger (bowls)."""
    lean = math.atan2(radius_top - radius_bottom, z1 - z0)
    length = math.hypot(radius_top - radius_bottom, z1 - z0)
    mid_radius = (radius_bottom + radius_top) / 2 - WALL / 2
    width = 2.0 * max(radius_bottom, radius_top) * math.tan(math.pi / PANELS) + WALL
    pieces = []
    for k in range(PANELS):
        angle = 2.0 * math.pi * k / PANELS
        rotation = Rotation.from_euler("zy", [angle, -lean])
        centre = [mid_radius * math.cos(angle), mid_radius * math.sin(angle), (z0 + z1) / 2]
        pieces.append(Piece("box", (WALL / 2, width / 2, length / 2), sapien.Pose(centre, _quat_wxyz(rotation))))
    return pieces


def pieces_of(spec: ObjectSpec) -> list[Piece]:
    """The convex pieces of an object, in its own frame (origin at the bounding-box centre)."""
    sx, sy, sz = spec.size
    bottom = -sz / 2
    if spec.type == "cup":
        radius = min(sx, sy) / 2
        return [_cylinder(radius, FLOOR / 2, bottom + FLOOR / 2), *_ring(radius, radius, bottom + FLOOR, sz / 2)]
    if spec.type == "bowl":
        radius = min(sx, sy) / 2
        return [
            _cylinder(radius * 0.55, FLOOR / 2, bottom + FLOOR / 2),
            *_ring(radius * 0.55, radius, bottom + FLOOR, sz / 2),
        ]
    if spec.type == "plate":
        return [_cylinder(min(sx, sy) / 2, sz / 2, 0.0)]
    if spec.open_top:
        wall_z = (bottom + FLOOR + sz / 2) / 2
        wall_half = (sz - FLOOR) / 2
        return [
            Piece("box", (sx / 2, sy / 2, FLOOR / 2), sapien.Pose([0, 0, bottom + FLOOR / 2])),
            Piece("box", (WALL / 2, sy / 2, wall_half), sapien.Pose([sx / 2 - WALL / 2, 0, wall_z])),
            Piece("box", (WALL / 2, sy / 2, wall_half), sapien.Pose([-sx / 2 + WALL / 2, 0, wall_z])),
            Piece("box", (sx / 2 - WALL, WALL / 2, wall_half), sapien.Pose([0, sy / 2 - WALL / 2, wall_z])),
            Piece("box", (sx / 2 - WALL, WALL / 2, wall_half), sapien.Pose([0, -sy / 2 + WALL / 2, wall_z])),
        ]
    return [Piece("box", (sx / 2, sy / 2, sz / 2), sapien.Pose())]


def build_object(scene: sapien.Scene, spec: ObjectSpec) -> sapien.Entity:
    """A dynamic body whose mass is the spec's, spread over its pieces by volume."""
    pieces = pieces_of(spec)
    density = spec.mass / sum(p.volume for p in pieces)
    material = sapien.physx.PhysxMaterial(spec.friction, spec.friction * 0.9, 0.0)
    colour = sapien.render.RenderMaterial(base_color=[*spec.rgb, 1.0], roughness=0.7, metallic=0.0)
    builder = scene.create_actor_builder()
    for piece in pieces:
        if piece.kind == "box":
            builder.add_box_collision(piece.pose, piece.half, material=material, density=density)
            builder.add_box_visual(piece.pose, piece.half, material=colour)
        else:
            builder.add_cylinder_collision(piece.pose, piece.half[0], piece.half[2], material=material, density=density)
            builder.add_cylinder_visual(piece.pose, piece.half[0], piece.half[2], material=colour)
    builder.set_name(spec.id)
    builder.set_initial_pose(sapien.Pose(list(spec.position), _quat_wxyz(Rotation.from_euler("z", spec.yaw))))
    return builder.build(name=spec.id)


def build_table(scene: sapien.Scene) -> sapien.Entity:
    """A static table: a top slab and four legs, clear of the robot's base."""
    material = sapien.physx.PhysxMaterial(TABLE_FRICTION, TABLE_FRICTION, 0.0)
    colour = sapien.render.RenderMaterial(base_color=[*TABLE_RGB, 1.0], roughness=0.9)
    leg_colour = sapien.render.RenderMaterial(base_color=[0.3, 0.3, 0.32, 1.0])
    (x0, x1), (y0, y1) = TABLE_X, TABLE_Y
    builder = scene.create_actor_builder()
    top_half = ((x1 - x0) / 2, (y1 - y0) / 2, TABLE_THICKNESS / 2)
    top_pose = sapien.Pose([(x0 + x1) / 2, (y0 + y1) / 2, TABLE_TOP_Z - TABLE_THICKNESS / 2])
    builder.add_box_collision(top_pose, top_half, material=material)
    builder.add_box_visual(top_pose, top_half, material=colour)
    leg_height = TABLE_TOP_Z - TABLE_THICKNESS
    for lx in (x0 + 0.05, x1 - 0.05):
        for ly in (y0 + 0.05, y1 - 0.05):
            leg = sapien.Pose([lx, ly, leg_height / 2])
            builder.add_box_collision(leg, (0.025, 0.025, leg_height / 2))
            builder.add_box_visual(leg, (0.025, 0.025, leg_height / 2), material=leg_colour)
    return builder.build_static(name="table")


def world_aabb(entity: sapien.Entity) -> np.ndarray:
    """(2, 3) min and max corners of the body's collision shapes in the world.

    Computed from the shapes themselves: PhysX bounds a cylinder by a box
    around it, so a plate turned about its axis by 45 degrees came out 1.4
    times as wide as it is.
    """
    body = entity.find_component_by_type(sapien.physx.PhysxRigidBaseComponent)
    lows, highs = [], []
    for shape in body.collision_shapes:
        pose = entity.pose * shape.get_local_pose()
        rotation = Rotation.from_quat(np.roll(pose.q, -1)).as_matrix()
        if isinstance(shape, sapien.physx.PhysxCollisionShapeCylinder):
            axis = rotation[:, 0]  # a SAPIEN cylinder runs along its local x
            half = shape.half_length * np.abs(axis) + shape.radius * np.sqrt(np.clip(1.0 - axis**2, 0.0, None))
        else:
            half = np.abs(rotation) @ np.asarray(shape.half_size, dtype=float)
        lows.append(pose.p - half)
        highs.append(pose.p + half)
    return np.array([np.min(lows, axis=0), np.max(highs, axis=0)], dtype=float)
