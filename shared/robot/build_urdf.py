"""Write the project's PR2 model (``pr2.urdf``) and its collision matrix (``pr2.srdf``).

Why generated: the kinematic chain, limits and proportions come from the PR2
fact sheet as numbers in this file, so the model can be checked and changed
in one place, and the SRDF (which link pairs a planner may ignore) is derived
from the very geometry it describes instead of being maintained by hand.

Shapes are primitives (boxes, cylinders); the gripper is two prismatic finger
pads per hand (0–0.045 m each, a 0–0.09 m gap) closing along the tool frame's
y axis. Continuous joints (forearm and wrist roll) are revolute with ±2π
limits so planners and IK see plain bounded joints.

Run ``python -m shared.robot.build_urdf`` after changing a number; names (joints, frames)
come from ``pr2.py``.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from itertools import combinations

import numpy as np

from shared.robot.pr2 import (
    ARM_PREFIX,
    ARMS,
    CAMERA_LINK,
    CAMERA_OPTICAL_FRAME,
    FINGER_TRAVEL,
    PR2,
    TOOL_OFFSET,
    TORSO_JOINT,
    arm_joint_names,
    tool_frame,
)

URDF_PATH = PR2.urdf_path
SRDF_PATH = PR2.srdf_path
TWO_PI = 2.0 * math.pi


# --- model description ------------------------------------------------------


@dataclass
class Shape:
    """A primitive: ``box`` (size xyz) or ``cylinder`` (radius, length along ``axis``)."""

    kind: str
    dims: tuple[float, ...]
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    axis: str = "z"  # cylinders only

    def rpy(self) -> tuple[float, float, float]:
        return {"z": (0.0, 0.0, 0.0), "x": (0.0, math.pi / 2, 0.0), "y": (math.pi / 2, 0.0, 0.0)}[self.axis]

    def inertia(self, mass: float) -> np.ndarray:
        """Diagonal inertia about the shape centre, in the link frame axes."""
        if self.kind == "box":
            x, y, z = self.dims
            return mass / 12.0 * np.array([y * y + z * z, x * x + z * z, x * x + y * y])
        radius, length = self.dims
        across = mass * (3 * radius * radius + length * length) / 12.0
        along = mass * radius * radius / 2.0
        return np.array([along if self.axis == a else across for a in "xyz"])


@dataclass
class Link:
    name: str
    mass: float = 0.0
    shapes: list[Shape] = field(default_factory=list)
    rgb: tuple[float, float, float] = (0.75, 0.75, 0.78)


@dataclass
class Joint:
    name: str
    kind: str  # revolute, prismatic, fixed
    parent: str
    child: str
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    lower: float = 0.0
    upper: float = 0.0
    velocity: float = 1.0
    effort: float = 30.0


X, Y, Z = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)
DARK = (0.18, 0.18, 0.2)
LIGHT = (0.82, 0.82, 0.85)
PAD = (0.3, 0.3, 0.3)


def box(x: float, y: float, z: float, at: tuple[float, float, float] = (0, 0, 0)) -> Shape:
    return Shape("box", (x, y, z), at)


def span_box(x: tuple[float, float], y: tuple[float, float], z: tuple[float, float]) -> Shape:
    """A box given by its extents along each axis (how the fact sheet lists them)."""
    return box(x[1] - x[0], y[1] - y[0], z[1] - z[0], ((x[0] + x[1]) / 2, (y[0] + y[1]) / 2, (z[0] + z[1]) / 2))


def body() -> tuple[list[Link], list[Joint]]:
    """Base, torso, head and the Kinect-like camera."""
    links = [
        Link("base_footprint"),
        Link(
            "base_link", 116.0, [box(0.668, 0.668, 0.23, (0, 0, 0.115)), box(0.08, 0.42, 0.43, (-0.25, 0, 0.445))], DARK
        ),
        Link(
            "torso_lift_link",
            36.2,
            [
                span_box((-0.212, -0.017), (-0.165, 0.165), (-0.45, 0.157)),
                span_box((-0.29, 0.11), (-0.26, 0.26), (0.157, 0.31)),
            ],
            LIGHT,
        ),
        Link("head_pan_link", 6.34, [span_box((-0.113, 0.145), (-0.161, 0.161), (-0.066, 0.079))], DARK),
        Link("head_tilt_link", 4.48, [span_box((-0.184, 0.077), (-0.148, 0.148), (-0.062, 0.155))], DARK),
        Link(CAMERA_LINK, 0.1, [box(0.06, 0.28, 0.04)], (0.1, 0.1, 0.1)),
        Link(CAMERA_OPTICAL_FRAME),
    ]
    joints = [
        Joint("base_footprint_joint", "fixed", "base_footprint", "base_link", (0, 0, 0.051)),
        Joint(
            TORSO_JOINT,
            "prismatic",
            "base_link",
            "torso_lift_link",
            (-0.05, 0, 0.739675),
            axis=Z,
            lower=0.0,
            upper=0.33,
            velocity=0.05,
            effort=10000.0,
        ),
        Joint(
            "head_pan_joint",
            "revolute",
            "torso_lift_link",
            "head_pan_link",
            (-0.01707, 0, 0.38145),
            axis=Z,
            lower=-3.007,
            upper=3.007,
            velocity=6.0,
            effort=2.645,
        ),
        Joint(
            "head_tilt_joint",
            "revolute",
            "head_pan_link",
            "head_tilt_link",
            (0.068, 0, 0),
            axis=Y,
            lower=-0.471,
            upper=1.396,
            velocity=5.0,
            effort=18.0,
        ),
        Joint("head_mount_kinect_rgb_joint", "fixed", "head_tilt_link", CAMERA_LINK, (-0.14707, -0.0175, 0.29195)),
        Joint(
            "head_mount_kinect_rgb_optical_frame_joint",
            "fixed",
            CAMERA_LINK,
            CAMERA_OPTICAL_FRAME,
            rpy=(-math.pi / 2, 0.0, -math.pi / 2),
        ),
    ]
    return links, joints


def arm(side: str) -> tuple[list[Link], list[Joint]]:
    """One 7-DoF arm with its gripper; the left arm mirrors the right."""
    p = ARM_PREFIX[side]
    side_sign = -1.0 if side == "right" else 1.0
    pan_limits = (-2.2854, 0.7146) if side == "right" else (-0.7146, 2.2854)
    roll_limits = (-3.9, 0.8) if side == "right" else (-0.8, 3.9)
    links = [
        Link(f"{p}_shoulder_pan_link", 25.8, [Shape("cylinder", (0.127, 0.40), (0, 0, -0.06))], LIGHT),
        Link(f"{p}_shoulder_lift_link", 2.75, [Shape("cylinder", (0.10, 0.153), axis="y")], DARK),
        Link(f"{p}_upper_arm_roll_link", 0.1),
        Link(f"{p}_upper_arm_link", 6.02, [box(0.34, 0.13, 0.15, (0.22, 0, 0))], LIGHT),
        Link(f"{p}_elbow_flex_link", 1.9, [span_box((-0.06, 0.08), (-0.047, 0.047), (-0.06, 0.06))], DARK),
        Link(f"{p}_forearm_roll_link", 0.1),
        Link(f"{p}_forearm_link", 2.58, [Shape("cylinder", (0.055, 0.20), (0.19, 0, 0), axis="x")], LIGHT),
        Link(f"{p}_wrist_flex_link", 0.61, [box(0.065, 0.042, 0.078)], DARK),
        Link(f"{p}_wrist_roll_link", 0.1),
        Link(f"{p}_gripper_palm_link", 0.58, [span_box((0.029, 0.125), (-0.05, 0.05), (-0.024, 0.024))], DARK),
        Link(f"{p}_gripper_l_finger_link", 0.2, [span_box((0.125, 0.20), (0.0, 0.01), (-0.013, 0.013))], PAD),
        Link(f"{p}_gripper_r_finger_link", 0.2, [span_box((0.125, 0.20), (-0.01, 0.0), (-0.013, 0.013))], PAD),
        Link(f"{p}_gripper_tool_frame"),
    ]
    joints = [
        Joint(
            f"{p}_shoulder_pan_joint",
            "revolute",
            "torso_lift_link",
            f"{p}_shoulder_pan_link",
            (0, side_sign * 0.188, 0),
            axis=Z,
            lower=pan_limits[0],
            upper=pan_limits[1],
            velocity=2.088,
            effort=30.0,
        ),
        Joint(
            f"{p}_shoulder_lift_joint",
            "revolute",
            f"{p}_shoulder_pan_link",
            f"{p}_shoulder_lift_link",
            (0.1, 0, 0),
            axis=Y,
            lower=-0.5236,
            upper=1.3963,
            velocity=2.082,
            effort=30.0,
        ),
        Joint(
            f"{p}_upper_arm_roll_joint",
            "revolute",
            f"{p}_shoulder_lift_link",
            f"{p}_upper_arm_roll_link",
            axis=X,
            lower=roll_limits[0],
            upper=roll_limits[1],
            velocity=3.27,
            effort=30.0,
        ),
        Joint(f"{p}_upper_arm_joint", "fixed", f"{p}_upper_arm_roll_link", f"{p}_upper_arm_link"),
        Joint(
            f"{p}_elbow_flex_joint",
            "revolute",
            f"{p}_upper_arm_link",
            f"{p}_elbow_flex_link",
            (0.4, 0, 0),
            axis=Y,
            lower=-2.3213,
            upper=0.0,
            velocity=3.3,
            effort=30.0,
        ),
        Joint(
            f"{p}_forearm_roll_joint",
            "revolute",
            f"{p}_elbow_flex_link",
            f"{p}_forearm_roll_link",
            axis=X,
            lower=-TWO_PI,
            upper=TWO_PI,
            velocity=3.6,
            effort=30.0,
        ),
        Joint(f"{p}_forearm_joint", "fixed", f"{p}_forearm_roll_link", f"{p}_forearm_link"),
        Joint(
            f"{p}_wrist_flex_joint",
            "revolute",
            f"{p}_forearm_link",
            f"{p}_wrist_flex_link",
            (0.321, 0, 0),
            axis=Y,
            lower=-2.18,
            upper=0.0,
            velocity=3.078,
            effort=10.0,
        ),
        Joint(
            f"{p}_wrist_roll_joint",
            "revolute",
            f"{p}_wrist_flex_link",
            f"{p}_wrist_roll_link",
            axis=X,
            lower=-TWO_PI,
            upper=TWO_PI,
            velocity=3.6,
            effort=10.0,
        ),
        Joint(f"{p}_gripper_palm_joint", "fixed", f"{p}_wrist_roll_link", f"{p}_gripper_palm_link"),
        Joint(
            f"{p}_gripper_l_finger_joint",
            "prismatic",
            f"{p}_gripper_palm_link",
            f"{p}_gripper_l_finger_link",
            axis=Y,
            lower=0.0,
            upper=FINGER_TRAVEL,
            velocity=0.1,
            effort=100.0,
        ),
        Joint(
            f"{p}_gripper_r_finger_joint",
            "prismatic",
            f"{p}_gripper_palm_link",
            f"{p}_gripper_r_finger_link",
            axis=(0.0, -1.0, 0.0),
            lower=0.0,
            upper=FINGER_TRAVEL,
            velocity=0.1,
            effort=100.0,
        ),
        Joint(f"{p}_gripper_tool_joint", "fixed", f"{p}_gripper_palm_link", tool_frame(side), (TOOL_OFFSET, 0, 0)),
    ]
    return links, joints


def model() -> tuple[list[Link], list[Joint]]:
    links, joints = body()
    for side in ARMS:
        more_links, more_joints = arm(side)
        links += more_links
        joints += more_joints
    return links, joints


# --- URDF -------------------------------------------------------------------


def _fmt(values: tuple[float, ...] | np.ndarray) -> str:
    return " ".join(f"{v:.6g}" for v in values)


def _shape_element(parent: ET.Element, tag: str, shape: Shape) -> ET.Element:
    element = ET.SubElement(parent, tag)
    ET.SubElement(element, "origin", xyz=_fmt(shape.xyz), rpy=_fmt(shape.rpy()))
    geometry = ET.SubElement(element, "geometry")
    if shape.kind == "box":
        ET.SubElement(geometry, "box", size=_fmt(shape.dims))
    else:
        ET.SubElement(geometry, "cylinder", radius=f"{shape.dims[0]:.6g}", length=f"{shape.dims[1]:.6g}")
    return element


def _link_element(robot: ET.Element, link: Link) -> None:
    element = ET.SubElement(robot, "link", name=link.name)
    mass = link.mass if link.mass > 0 else 0.01
    centre = np.mean([s.xyz for s in link.shapes], axis=0) if link.shapes else np.zeros(3)
    if link.shapes:
        # each shape carries an equal share of the mass; parallel-axis about the centre
        share = mass / len(link.shapes)
        diag = sum(
            s.inertia(share) + share * (np.sum((np.array(s.xyz) - centre) ** 2) - (np.array(s.xyz) - centre) ** 2)
            for s in link.shapes
        )
    else:
        diag = np.full(3, 1e-5)
    inertial = ET.SubElement(element, "inertial")
    ET.SubElement(inertial, "origin", xyz=_fmt(centre), rpy="0 0 0")
    ET.SubElement(inertial, "mass", value=f"{mass:.6g}")
    ET.SubElement(
        inertial, "inertia", ixx=f"{diag[0]:.6g}", ixy="0", ixz="0", iyy=f"{diag[1]:.6g}", iyz="0", izz=f"{diag[2]:.6g}"
    )
    for index, shape in enumerate(link.shapes):
        visual = _shape_element(element, "visual", shape)
        material = ET.SubElement(visual, "material", name=f"{link.name}_{index}")
        ET.SubElement(material, "color", rgba=_fmt((*link.rgb, 1.0)))
        _shape_element(element, "collision", shape)


def _joint_element(robot: ET.Element, joint: Joint) -> None:
    element = ET.SubElement(robot, "joint", name=joint.name, type=joint.kind)
    ET.SubElement(element, "parent", link=joint.parent)
    ET.SubElement(element, "child", link=joint.child)
    ET.SubElement(element, "origin", xyz=_fmt(joint.xyz), rpy=_fmt(joint.rpy))
    if joint.kind != "fixed":
        ET.SubElement(element, "axis", xyz=_fmt(joint.axis))
        ET.SubElement(
            element,
            "limit",
            lower=f"{joint.lower:.6g}",
            upper=f"{joint.upper:.6g}",
            velocity=f"{joint.velocity:.6g}",
            effort=f"{joint.effort:.6g}",
        )
        ET.SubElement(element, "dynamics", damping="0.1", friction="0.0")


def urdf_text(links: list[Link], joints: list[Joint]) -> str:
    robot = ET.Element("robot", name="pr2")
    robot.append(ET.Comment(" Generated by shared/robot/build_urdf.py from the PR2 fact sheet; do not edit. "))
    for link in links:
        _link_element(robot, link)
    for joint in joints:
        _joint_element(robot, joint)
    ET.indent(robot)
    return ET.tostring(robot, encoding="unicode") + "\n"


# --- SRDF -------------------------------------------------------------------


def _adjacent_pairs(links: list[Link], joints: list[Joint]) -> set[frozenset[str]]:
    """Pairs of links with geometry joined by one joint, looking through geometry-less links."""
    parent_of = {j.child: j.parent for j in joints}
    has_geometry = {link.name: bool(link.shapes) for link in links}

    def solid_ancestor(name: str) -> str | None:
        while name in parent_of:
            name = parent_of[name]
            if has_geometry[name]:
                return name
        return None

    pairs = set()
    for link in links:
        if link.shapes and (ancestor := solid_ancestor(link.name)) is not None:
            pairs.add(frozenset((link.name, ancestor)))
    return pairs


def _near_pairs(links: list[Link], joints: list[Joint]) -> set[frozenset[str]]:
    """Pairs of links with geometry in one arm, at most two actuated joints apart.

    The primitive shapes overlap where the real links nest (shoulder into upper
    arm, upper arm into forearm at full flex, forearm into palm); the joint
    limits, not the shapes, keep such links apart, so planners ignore them.
    The two finger pads of one hand touch whenever the gripper is shut.
    """
    parent_joint = {j.child: j for j in joints}
    solid = {link.name for link in links if link.shapes}

    def chain(name: str) -> list[tuple[str, int]]:
        """``name`` and its ancestors with the number of actuated joints crossed."""
        crossed, out = 0, [(name, 0)]
        while name in parent_joint:
            joint = parent_joint[name]
            crossed += joint.kind != "fixed"
            name = joint.parent
            out.append((name, crossed))
        return out

    pairs = set()
    for link in solid:
        for ancestor, crossed in chain(link)[1:]:
            if ancestor in solid and crossed <= 2:
                pairs.add(frozenset((link, ancestor)))
    for side in ARMS:
        p = ARM_PREFIX[side]
        pairs.add(frozenset((f"{p}_gripper_l_finger_link", f"{p}_gripper_r_finger_link")))
    return pairs


def _sampled_pairs(
    known: set[frozenset[str]], samples: int, seed: int
) -> tuple[set[frozenset[str]], set[frozenset[str]]]:
    """Link pairs colliding at the zero pose ("default") and in ≥ 95 % of random poses ("always").

    The planner is loaded with the ``known`` pairs already disabled (an SRDF
    must exist, or mplib generates its own); the URDF must be written first.
    """
    import mplib  # planning library; only needed when regenerating

    SRDF_PATH.write_text(_srdf_document({pair: "Adjacent" for pair in known}))
    planner = mplib.Planner(urdf=str(URDF_PATH), srdf=str(SRDF_PATH), move_group=tool_frame("right"))
    per_joint: list[np.ndarray] = list(planner.pinocchio_model.get_joint_limits())
    limits = np.array([lim for joint_limits in per_joint for lim in joint_limits])
    rng = np.random.default_rng(seed)

    def colliding(qpos: np.ndarray) -> set[frozenset[str]]:
        return {frozenset((r.link_name1, r.link_name2)) for r in planner.check_for_self_collision(qpos)}

    default = colliding(np.clip(np.zeros(len(limits)), limits[:, 0], limits[:, 1]))
    counts: dict[frozenset[str], int] = {}
    for _ in range(samples):
        for pair in colliding(rng.uniform(limits[:, 0], limits[:, 1])):
            counts[pair] = counts.get(pair, 0) + 1
    always = {pair for pair, n in counts.items() if n >= 0.95 * samples}
    return default, always


def _srdf_document(reasons: dict[frozenset[str], str]) -> str:
    robot = ET.Element("robot", name="pr2")
    robot.append(ET.Comment(" Generated by shared/robot/build_urdf.py; do not edit. "))
    for side in ARMS:
        group = ET.SubElement(robot, "group", name=f"{side}_arm")
        for name in arm_joint_names(side):
            ET.SubElement(group, "joint", name=name)
    for pair in sorted(reasons, key=lambda pair: sorted(pair)):
        first, second = sorted(pair)
        ET.SubElement(robot, "disable_collisions", link1=first, link2=second, reason=reasons[pair])
    ET.indent(robot)
    return ET.tostring(robot, encoding="unicode") + "\n"


def srdf_text(links: list[Link], joints: list[Joint], samples: int = 400, seed: int = 0) -> str:
    """The collision matrix: adjacent links, the fixed body, and pairs found colliding by sampling."""
    body_links = {
        "base_link",
        "torso_lift_link",
        "head_pan_link",
        "head_tilt_link",
        CAMERA_LINK,
        "r_shoulder_pan_link",
        "l_shoulder_pan_link",
        "r_shoulder_lift_link",
        "l_shoulder_lift_link",
    }
    # the shoulders sit in the torso and the head on it: their contacts with the
    # body are part of the build (the real robot nests them), not something a planner can avoid
    reasons = {pair: "Near" for pair in _near_pairs(links, joints)}
    reasons.update({frozenset(pair): "Body" for pair in combinations(sorted(body_links), 2)})
    reasons.update({pair: "Adjacent" for pair in _adjacent_pairs(links, joints)})
    default, always = _sampled_pairs(set(reasons), samples, seed)
    reasons.update({pair: "Default" for pair in default})
    reasons.update({pair: "Always" for pair in always})
    return _srdf_document(reasons)


def main() -> None:
    links, joints = model()
    URDF_PATH.write_text(urdf_text(links, joints))
    SRDF_PATH.write_text(srdf_text(links, joints))  # needs the URDF on disk
    print(f"wrote {URDF_PATH} and {SRDF_PATH}")


if __name__ == "__main__":
    main()
