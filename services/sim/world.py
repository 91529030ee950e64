"""The simulated world: a PR2 at a table with objects, stepped by PhysX and seen by a head camera.

Why one class owns the SAPIEN scene: SAPIEN is not thread-safe, so every
touch of the scene (stepping, drives, rendering, loading objects) happens on
the one thread that owns a ``SimWorld``; the service feeds it commands from
a queue. Grasps are physical: the fingers are position-driven with a force
limit, and an object stays in the hand only through friction at the pads.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import count
from typing import Any

import numpy as np
import sapien
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation

from services.sim import objects as object_builder
from services.sim.halt import Halting
from services.sim.motion import SPEED_FRACTION, MinimumJerk, Motion, Waypoints
from services.sim.scene_file import ObjectSpec, SceneSpec
from shared.robot import ROBOT
from shared.robot.build_urdf import model

ARMS = ROBOT.arms
# the model's joints from the floor to the head camera, for aiming the head (origins in the parent frame)
_HEAD_CHAIN = ("base_footprint_joint", ROBOT.torso_joint, *ROBOT.head_joints, "head_mount_kinect_rgb_joint")
_ORIGINS = {joint.name: np.array(joint.xyz, float) for joint in model()[1] if joint.name in _HEAD_CHAIN}

TIMESTEP = 1.0 / 250.0
GRIPPER_SPEED = 0.15  # gap closing/opening speed (m/s): three quarters of the rated 0.2
PAD_FRICTION = 1.5
GRIPPER_SETTLE_TRAVEL = 0.0005  # m: the pads have stopped when the opening changes less than this
GRIPPER_SETTLE_TIME = 0.15  # s ... over this long
ROBOT_IGNORE_BIT = 1 << 30  # collision group 2 bit shared by all robot shapes
SQUEEZE_ALIGNMENT = 0.7  # |cos| between a pad contact's normal and the closing axis for a squeeze

# joint drives: (stiffness, damping, force limit); gravity is off for the robot's
# links (a real PR2 is counterbalanced), so the drives only fight contacts and loads
ARM_DRIVE = (3000.0, 150.0)
WRIST_DRIVE = (1000.0, 50.0)
HEAD_DRIVE = (800.0, 80.0, 50.0)
TORSO_DRIVE = (2.0e5, 2.0e4, 1.0e4)
FINGER_DRIVE = (2000.0, 150.0)


@dataclass(frozen=True)
class JointInfo:
    name: str
    index: int
    lower: float
    upper: float
    velocity: float
    effort: float


@dataclass
class Capture:
    """One head-camera frame as the renderer gives it (converted to a cloud elsewhere)."""

    position: np.ndarray  # (H, W, 4) camera-frame xyz (OpenGL axes) + depth
    color: np.ndarray  # (H, W, 4) float 0..1
    model_matrix: np.ndarray  # (4, 4) OpenGL camera frame -> world
    camera_pose: list[float]  # camera link pose (x forward, y left, z up), base frame
    sim_time: float
    scene: str = ""  # the scene shown and which load of it, so a frame rendered
    scene_generation: int = 0  # just before a reload is never taken for the new scene
    segmentation: np.ndarray | None = None  # (H, W) entity ids (tests only)


@dataclass(frozen=True, eq=False)
class PictureInFlight:
    """A head-camera frame being rendered: what :class:`Capture` will say besides its pixels."""

    model_matrix: np.ndarray
    camera_pose: list[float]
    sim_time: float
    scene: str
    scene_generation: int


def pose_list(pose: sapien.Pose) -> list[float]:
    return [float(v) for v in (*pose.p, *pose.q)]


def look_rotation(eye: np.ndarray, target: np.ndarray) -> list[float]:
    """Quaternion (w, x, y, z) turning a camera's x axis towards ``target`` with z kept up."""
    forward = (target - eye) / np.linalg.norm(target - eye)
    left = np.cross([0.0, 0.0, 1.0], forward)
    left /= np.linalg.norm(left)
    up = np.cross(forward, left)
    x, y, z, w = Rotation.from_matrix(np.column_stack([forward, left, up])).as_quat()
    return [w, x, y, z]


class SimWorld:
    """The SAPIEN scene with its robot, table, objects, camera and running motions."""

    def __init__(self, width: int = 640, height: int = 480, timestep: float = TIMESTEP) -> None:
        sapien.physx.set_scene_config(enable_tgs=True, enable_friction_every_iteration=True)
        sapien.physx.set_body_config(solver_position_iterations=20, solver_velocity_iterations=2)
        sapien.physx.set_shape_config(contact_offset=0.004, rest_offset=0.0)
        self.scene = sapien.Scene()
        self.scene.set_timestep(timestep)
        self.timestep = timestep
        self.scene.set_ambient_light([0.45, 0.45, 0.45])
        self.scene.add_directional_light([0.3, 0.4, -1.0], [0.75, 0.75, 0.75])
        self.scene.add_point_light([0.6, 0.0, 2.2], [0.6, 0.6, 0.6])
        self.scene.add_ground(0.0, render_half_size=[3, 3])
        self.table = object_builder.build_table(self.scene)
        self.robot = self._load_robot()
        self.joints = self._joint_info()
        self.links = {link.name: link for link in self.robot.get_links()}
        self.camera = self._mount_camera(width, height)
        self.overview: sapien.render.RenderCameraComponent | None = None
        self._in_flight: PictureInFlight | None = None
        self.objects: dict[str, sapien.Entity] = {}
        self.specs: dict[str, ObjectSpec] = {}
        self.scene_name = ""
        self.scene_generation = 0  # counts loads, so a reload of the same scene is visible too
        self.motions: dict[str, Motion] = {}
        self.grip_force = {arm: ROBOT.gripper.default_effort for arm in ARMS}
        self.sim_time = 0.0
        self.halting = Halting()
        self.came_to_rest = False  # this step, the joints last told to stop came to rest
        self._ids = count(1)
        self.home()

    # -- construction --------------------------------------------------------
    def _load_robot(self) -> sapien.physx.PhysxArticulation:
        loader = self.scene.create_urdf_loader()
        loader.fix_root_link = True
        # the SRDF is for planners only: physics ignores self-contact (below)
        robot = loader.load(str(ROBOT.urdf_path), srdf_file="")
        robot.set_name("pr2")
        pad_material = sapien.physx.PhysxMaterial(PAD_FRICTION, PAD_FRICTION, 0.0)
        pads = {name for arm in ARMS for name in self.pad_links(arm)}
        for link in robot.get_links():
            link.disable_gravity = True
            for shape in link.collision_shapes:
                groups = shape.get_collision_groups()
                groups[2] |= ROBOT_IGNORE_BIT
                shape.set_collision_groups(groups)
                if link.name in pads:
                    shape.set_physical_material(pad_material)
        for joint in robot.get_active_joints():
            name = joint.name
            if "finger" in name:
                joint.set_drive_properties(*FINGER_DRIVE, ROBOT.gripper.default_effort)
            elif name == "torso_lift_joint":
                joint.set_drive_properties(*TORSO_DRIVE)
            elif name.startswith("head"):
                joint.set_drive_properties(*HEAD_DRIVE)
            elif "wrist" in name:
                joint.set_drive_properties(*WRIST_DRIVE, 3.0 * 10.0)
            else:
                joint.set_drive_properties(*ARM_DRIVE, 3.0 * 30.0)
        return robot

    def _joint_info(self) -> dict[str, JointInfo]:
        _, joint_specs = model()
        by_name = {j.name: j for j in joint_specs}
        info = {}
        for index, joint in enumerate(self.robot.get_active_joints()):
            spec = by_name[joint.name]
            info[joint.name] = JointInfo(joint.name, index, spec.lower, spec.upper, spec.velocity, spec.effort)
        return info

    def _mount_camera(self, width: int, height: int) -> sapien.render.RenderCameraComponent:
        spec = ROBOT.camera
        camera = self.scene.add_mounted_camera(
            "head_camera",
            self.links[spec.link].entity,
            sapien.Pose(),
            width,
            height,
            spec.vertical_fov(width, height),
            0.05,
            spec.far + 1.0,
        )
        return camera

    @staticmethod
    def pad_links(arm: str) -> list[str]:
        p = arm[0]
        return [f"{p}_gripper_l_finger_link", f"{p}_gripper_r_finger_link"]

    # -- robot posture ---------------------------------------------------------
    def home(self) -> None:
        """Torso up, arms to the side, grippers open, head on the table: the start posture."""
        start = ROBOT.keyframe("start")
        targets = dict(start.joints)
        pan, tilt = self.head_angles_for(np.array(start.gaze), targets[ROBOT.torso_joint])
        targets.update(zip(ROBOT.head_joints, (pan, tilt), strict=True))
        qpos = np.zeros(len(self.joints))
        for name, value in targets.items():
            qpos[self.joints[name].index] = value
        self.robot.set_qpos(qpos)
        self.robot.set_qvel(np.zeros(len(self.joints)))
        for name, value in targets.items():
            joint = self.robot.get_active_joints()[self.joints[name].index]
            joint.set_drive_target(value)
            joint.set_drive_velocity_target(0.0)

    def qpos(self, names: list[str]) -> np.ndarray:
        q = self.robot.get_qpos()
        return np.array([q[self.joints[n].index] for n in names])

    def joint_targets(self, names: list[str]) -> np.ndarray:
        """Where the drives are told to be (a new motion starts here, so holding forces stay)."""
        active = self.robot.get_active_joints()
        return np.array([float(np.asarray(active[self.joints[n].index].drive_target).reshape(-1)[0]) for n in names])

    def head_angles_for(self, target: np.ndarray, torso: float | None = None) -> tuple[float, float]:
        """Pan and tilt that put ``target`` on the head camera's optical axis (clamped to the limits)."""
        torso = self.qpos([ROBOT.torso_joint])[0] if torso is None else torso
        base, lift, pan_joint, tilt_joint, camera = (_ORIGINS[name] for name in _HEAD_CHAIN)
        pan_axis = base + lift + pan_joint + np.array([0.0, 0.0, torso])
        offset = target - pan_axis
        pan = float(
            np.clip(
                math.atan2(offset[1], offset[0]),
                self.joints["head_pan_joint"].lower,
                self.joints["head_pan_joint"].upper,
            )
        )
        ahead = math.hypot(offset[0], offset[1]) - tilt_joint[0]
        rise = offset[2]
        cam_x, cam_z = camera[0], camera[2]  # the camera's small sideways offset is neglected

        def miss(tilt: float) -> float:
            c, s = math.cos(tilt), math.sin(tilt)
            eye_x, eye_z = cam_x * c + cam_z * s, -cam_x * s + cam_z * c
            return c * (rise - eye_z) + s * (ahead - eye_x)

        low, high = self.joints["head_tilt_joint"].lower, self.joints["head_tilt_joint"].upper
        if miss(low) * miss(high) > 0:
            tilt = low if abs(miss(low)) < abs(miss(high)) else high
        else:
            tilt = brentq(miss, low, high)
        return pan, float(tilt)

    # -- motions ---------------------------------------------------------------
    def new_motion_id(self) -> str:
        return f"m{next(self._ids)}"

    def start_motion(self, motion: Motion) -> Motion | None:
        """Run ``motion``; returns the motion it replaced on the same part, if any."""
        replaced = self.motions.pop(motion.part, None)
        self.motions[motion.part] = motion
        return replaced

    def move_joints(
        self, part: str, names: list[str], goal: np.ndarray, motion_id: str, speed_fraction: float = SPEED_FRACTION
    ) -> Motion | None:
        """A rest-to-rest move of ``names`` to ``goal``, its fastest joint at ``speed_fraction`` of its rated speed."""
        start = self.joint_targets(names)
        velocity = np.array([self.joints[n].velocity for n in names])
        return self.start_motion(
            Motion(motion_id, part, names, MinimumJerk(start, goal, velocity, speed_fraction), self.sim_time)
        )

    def follow_waypoints(
        self, part: str, names: list[str], times: np.ndarray, points: np.ndarray, motion_id: str, contact: bool = False
    ) -> Motion | None:
        """Follow timed waypoints; ``contact``: the motion may end pressed against an object (a press)."""
        if times[0] > 0:  # start from where the joints are now
            times = np.concatenate([[0.0], times])
            points = np.vstack([self.joint_targets(names), points])
        else:
            points = points.copy()
            points[0] = self.joint_targets(names)
        return self.start_motion(Motion(motion_id, part, names, Waypoints(times, points), self.sim_time, contact))

    def move_gripper(self, arm: str, width: float, force: float, motion_id: str) -> Motion | None:
        names = ROBOT.finger_joint_names(arm)
        start = self.joint_targets(names)
        goal = np.full(2, width / 2)
        self.grip_force[arm] = force
        for name in names:
            joint = self.robot.get_active_joints()[self.joints[name].index]
            joint.set_drive_properties(*FINGER_DRIVE, force)
        # pads move at a fixed speed; the force limit, not the reference, stops them on contact
        velocity = np.full(2, 1.875 * GRIPPER_SPEED / 2)  # minimum jerk: peak = 1.875 × mean
        return self.start_motion(
            GripperMotion(
                motion_id, f"{arm}_gripper", names, MinimumJerk(start, goal, velocity, 1.0), self.sim_time, arm=arm
            )
        )

    def stop(self, parts: list[str]) -> list[Motion]:
        """Stop the motions of ``parts`` where the joints are now."""
        stopped = []
        active = self.robot.get_active_joints()
        for part in parts:
            motion = self.motions.pop(part, None)
            if motion is None:
                continue
            stopped.append(motion)
            if isinstance(motion, GripperMotion):
                continue  # a gripper keeps squeezing what it holds
            for name, value in zip(motion.joints, self.qpos(motion.joints)):
                active[self.joints[name].index].set_drive_target(float(value))
                active[self.joints[name].index].set_drive_velocity_target(0.0)
            self.halting.stopped([self.joints[name].index for name in motion.joints], self.sim_time)
        return stopped

    # -- stepping ----------------------------------------------------------------
    def step(self) -> list[tuple[Motion, str, str]]:
        """Advance physics one step; returns finished motions with their status and message."""
        active = self.robot.get_active_joints()
        for motion in self.motions.values():
            position, velocity = motion.reference(self.sim_time)
            for name, p, v in zip(motion.joints, position, velocity):
                joint = active[self.joints[name].index]
                joint.set_drive_target(float(p))
                joint.set_drive_velocity_target(float(v))
        self.scene.step()
        self.sim_time += self.timestep
        self.came_to_rest = self.halting.watching and self.halting.came_to_rest(self.robot.get_qvel(), self.sim_time)
        finished = []
        for part, motion in list(self.motions.items()):
            if isinstance(motion, GripperMotion):
                result = motion.gripper_outcome(self.sim_time, self)
            elif motion.contact and self.sim_time - motion.start_time >= motion.trajectory.duration:
                result = motion.contact_outcome(self.sim_time, self.qpos(motion.joints), self.arm_touching(part))
            else:
                result = motion.outcome(self.sim_time, self.qpos(motion.joints))
            if result is not None:
                del self.motions[part]
                finished.append((motion, *result))
        return finished

    # -- scene -------------------------------------------------------------------
    def load(self, scene: SceneSpec) -> None:
        """Replace the objects by those of ``scene`` and put the robot in its start posture."""
        self._wait_for_picture()
        for entity in self.objects.values():
            self.scene.remove_entity(entity)
        self.objects.clear()
        self.specs.clear()
        self.motions.clear()
        self.home()
        for spec in scene.objects:
            self.objects[spec.id] = object_builder.build_object(self.scene, spec)
            self.specs[spec.id] = spec
        self.scene_name = scene.name
        self.scene_generation += 1

    def settle(self, seconds: float = 0.5) -> None:
        for _ in range(int(seconds / self.timestep)):
            self.step()

    # -- reading -----------------------------------------------------------------
    def contacts_by_link(self, links: set[str], contacts: Sequence[Any] | None = None) -> dict[str, set[str]]:
        """Object ids touching each of ``links`` (any contact point closer than 2 mm).

        ``contacts`` is this step's contact list when the caller already has
        it: asking PhysX again for every question would repeat the whole pass.
        """
        touching: dict[str, set[str]] = {name: set() for name in links}
        for contact in self.scene.get_contacts() if contacts is None else contacts:
            names = [body.entity.name for body in contact.bodies]
            for mine, other in (names, names[::-1]):
                if mine in links and other in self.objects:
                    if any(point.separation < 0.002 for point in contact.points):
                        touching[mine].add(other)
        return touching

    def arm_touching(self, arm: str) -> list[str]:
        """Objects touching any link of ``arm`` (what a pressing hand rests against)."""
        prefix = f"{arm[0]}_"
        links = {name for name, link in self.links.items() if name.startswith(prefix) and link.collision_shapes}
        return sorted(set().union(*self.contacts_by_link(links).values()))

    def squeezed(self, arm: str, contacts: Sequence[Any] | None = None) -> set[str]:
        """Objects held between both of ``arm``'s pads.

        A pad touching an object with its tip (a hand pressed against a box's
        side, fingertips on a plate) does not hold it: a contact counts as a
        squeeze when its normal runs along the closing axis, so a box pressed
        between two hands is held by neither gripper alone. An object both
        pads touch at their edges (a box caught by its rims, deep between the
        fingers) is held too when nothing but this gripper touches it: nothing
        else carries it. ``contacts`` as for :meth:`contacts_by_link`.
        """
        tool = self.links[ROBOT.tool_frame(arm)].entity_pose
        closing = Rotation.from_quat(np.roll(tool.q, -1)).apply([0.0, 1.0, 0.0])
        pads = set(self.pad_links(arm))
        gripper = f"{arm[0]}_gripper"
        faces: dict[str, set[str]] = {name: set() for name in pads}
        touched: dict[str, set[str]] = {name: set() for name in pads}
        carried_elsewhere: set[str] = set()
        for contact in self.scene.get_contacts() if contacts is None else contacts:
            near = [point for point in contact.points if point.separation < 0.002]
            if not near:
                continue
            names = [body.entity.name for body in contact.bodies]
            for mine, other in (names, names[::-1]):
                if other not in self.objects:
                    continue
                if mine in pads:
                    touched[mine].add(other)
                    if any(abs(float(np.dot(point.normal, closing))) > SQUEEZE_ALIGNMENT for point in near):
                        faces[mine].add(other)
                elif not mine.startswith(gripper):
                    carried_elsewhere.add(other)
        return set.intersection(*faces.values()) | (set.intersection(*touched.values()) - carried_elsewhere)

    def gripper_width(self, arm: str) -> float:
        return float(self.qpos(ROBOT.finger_joint_names(arm)).sum())

    def gripper_effort(self, arm: str) -> float:
        """How hard the pads squeeze (N, closing positive): what a gripper motor's current tells a real robot.

        Each pad's drive pushes with its PD law towards the drive target,
        bounded by the grip's force limit; a pad blocked by an object pushes
        at the limit, a pad moving freely or at rest at its goal barely at
        all. The lesser of the two pads is reported: both must press for the
        hand to squeeze anything.
        """
        active = self.robot.get_active_joints()
        qpos, qvel = self.robot.get_qpos(), self.robot.get_qvel()
        squeeze = []
        for name in ROBOT.finger_joint_names(arm):
            index = self.joints[name].index
            joint = active[index]
            target = float(np.asarray(joint.drive_target).reshape(-1)[0])
            target_velocity = float(np.asarray(joint.drive_velocity_target).reshape(-1)[0])
            push = joint.stiffness * (target - qpos[index]) + joint.damping * (target_velocity - qvel[index])
            squeeze.append(-float(np.clip(push, -joint.force_limit, joint.force_limit)))  # a pad opens along +q
        return min(squeeze)

    def state(self) -> dict:
        """Everything ``sim/state`` carries except the stamp and the real-time factor."""
        qpos, qvel = self.robot.get_qpos(), self.robot.get_qvel()
        joints = {name: float(qpos[info.index]) for name, info in self.joints.items()}
        pads = {name for arm in ARMS for name in self.pad_links(arm)}
        contacts = self.scene.get_contacts()
        touching = self.contacts_by_link(pads, contacts)
        grippers = {}
        for arm in ARMS:
            left, right = (touching[name] for name in self.pad_links(arm))
            both = sorted(self.squeezed(arm, contacts))
            grippers[arm] = {
                "width": self.gripper_width(arm),
                "effort": self.gripper_effort(arm),
                "holding": both[0] if both else None,
                "contact": sorted(left | right),
                "force": self.grip_force[arm],
            }
        links = {
            name: pose_list(link.entity_pose)
            for name, link in self.links.items()
            if name[:2] in ("r_", "l_") and (link.collision_shapes or name.endswith("tool_frame"))
        }
        return {
            "sim_time": self.sim_time,
            "joints": joints,
            "velocities": {name: float(qvel[info.index]) for name, info in self.joints.items()},
            "ee": {arm: pose_list(self.links[ROBOT.tool_frame(arm)].entity_pose) for arm in ARMS},
            "grippers": grippers,
            "moving": {arm: arm in self.motions for arm in ARMS},
            "head": {"pan": joints["head_pan_joint"], "tilt": joints["head_tilt_joint"]},
            "torso": joints["torso_lift_joint"],
            "links": links,
            "scene": self.scene_name,
            "scene_generation": self.scene_generation,
        }

    def truth(self) -> list[dict]:
        """Ground-truth objects: world-state fields plus pose and the world bounding box."""
        out = []
        for object_id, entity in self.objects.items():
            spec = self.specs[object_id]
            box = object_builder.world_aabb(entity)
            out.append(
                {
                    "id": object_id,
                    "color": spec.color,
                    "type": spec.type,
                    "position": [float(v) for v in (box[0] + box[1]) / 2],
                    "size": [float(v) for v in box[1] - box[0]],
                    "dimensions": list(spec.size),
                    "pose": pose_list(entity.pose),
                    "aabb": box.tolist(),
                    "entity_id": int(entity.per_scene_id),
                }
            )
        return out

    def take_picture(self) -> PictureInFlight:
        """Start rendering the head camera and return at once: the renderer works on its own threads.

        Why split from reading: reading the pixels waits for the renderer, and
        the service's loop must keep stepping physics and taking requests (a
        stop above all) meanwhile; it reads once :class:`RenderWait` says the
        frame is done. The frame shows the world as it is now.
        """
        self._wait_for_picture()
        self.scene.update_render()
        self.camera.take_picture()
        self._in_flight = PictureInFlight(
            model_matrix=np.asarray(self.camera.get_model_matrix(), dtype=np.float64),
            camera_pose=pose_list(self.links[ROBOT.camera.link].entity_pose),
            sim_time=self.sim_time,
            scene=self.scene_name,
            scene_generation=self.scene_generation,
        )
        return self._in_flight

    def read_picture(self, picture: PictureInFlight, segmentation: bool = False) -> Capture | None:
        """The pixels of ``picture`` (waiting for the renderer if it is not done), or None when it was dropped."""
        if picture is not self._in_flight:
            return None  # a reload or another render came first and dropped it
        self._in_flight = None
        return Capture(
            position=self.camera.get_picture("Position"),
            color=self.camera.get_picture("Color"),
            model_matrix=picture.model_matrix,
            camera_pose=picture.camera_pose,
            sim_time=picture.sim_time,
            scene=picture.scene,
            scene_generation=picture.scene_generation,
            segmentation=self.camera.get_picture("Segmentation")[..., 1].copy() if segmentation else None,
        )

    def capture(self, segmentation: bool = False) -> Capture:
        """Render the head camera and wait for it (the caller turns it into a cloud off this thread)."""
        capture = self.read_picture(self.take_picture(), segmentation)
        assert capture is not None  # nothing can come between taking and reading it here
        return capture

    def _wait_for_picture(self) -> None:
        """Let a render in flight finish, and drop it, before anything else touches what it draws."""
        if self._in_flight is not None:
            self.camera.get_picture("Position")
            self._in_flight = None

    def overview_rgb(self, width: int = 800, height: int = 600) -> np.ndarray:
        """An RGB picture (uint8) of the robot and table from the front-left, for people."""
        if self.overview is None:
            eye, target = np.array([1.9, 1.1, 1.75]), np.array([0.45, 0.0, 0.75])
            self.overview = self.scene.add_camera("overview", width, height, math.radians(45.0), 0.05, 10.0)
            self.overview.entity.set_pose(sapien.Pose(eye, look_rotation(eye, target)))
        self._wait_for_picture()
        self.scene.update_render()
        self.overview.take_picture()
        rgba = self.overview.get_picture("Color")
        return (np.clip(rgba[..., :3], 0.0, 1.0) * 255).astype(np.uint8)


class GripperMotion(Motion):
    """A gripper move that finishes when the pads stop: at the goal, or squeezing something."""

    def __init__(self, *args, arm: str, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.arm = arm
        self._watch: tuple[float, float] | None = None  # (time, width) when the pads were last seen moving

    def gripper_outcome(self, now: float, world: SimWorld) -> tuple[str, str] | None:
        if now - self.start_time < self.trajectory.duration:
            return None
        # joint velocities jitter while squeezing, so "stopped" is judged from the opening itself
        width = world.gripper_width(self.arm)
        if self._watch is None or abs(width - self._watch[1]) > GRIPPER_SETTLE_TRAVEL:
            self._watch = (now, width)
            return None
        if now - self._watch[0] < GRIPPER_SETTLE_TIME:
            return None
        width = world.gripper_width(self.arm)
        goal = float(self.goal.sum())
        if abs(width - goal) <= 0.003:
            return "done", f"{self.arm} gripper at {width:.3f} m"
        held = world.squeezed(self.arm)
        if held:
            return "done", f"{self.arm} gripper holding {sorted(held)[0]} at {width:.3f} m"
        return "failed", f"{self.arm} gripper was blocked at {width:.3f} m (goal {goal:.3f} m)"
