"""Where things are: the table, the robot's working posture and its named arm poses.

One place for the numbers other parts rely on (the executor plans for this
torso height, perception crops at this table height). World frame == robot
base frame: the robot stands fixed at the origin, x forward, y left, z up,
z = 0 on the floor.
"""

from __future__ import annotations

from services.sim.robot.build_urdf import ARMS, arm_joint_names

TABLE_TOP_Z = 0.72                 # a real table (0.72–0.76 m), worked with the torso raised
TABLE_THICKNESS = 0.04
TABLE_X = (0.35, 1.15)             # near and far edge; the near edge clears the base (x ≤ 0.334)
TABLE_Y = (-0.80, 0.80)
TORSO_HEIGHT = 0.33                # torso fully up: shoulders at 1.121 m, 0.40 m above the table
HEAD_LOOK_AT = (0.60, 0.0, TABLE_TOP_Z)  # where the head looks at start: the middle of the work area

# Named arm poses (shoulder pan … wrist roll), right arm; the left mirrors it.
_MIRROR = (-1.0, 1.0, -1.0, 1.0, -1.0, 1.0, -1.0)
_RIGHT_POSES: dict[str, tuple[float, ...]] = {
    # out of the camera's view of the table, gripper clear of the table top
    "side": (-2.110, 1.230, -2.06, -1.69, 0.3, -1.32, 1.57),
    # in front of the body, above the table's near edge
    "untucked": (-0.4, 1.0, 0.0, -2.05, 0.0, -0.1, 0.0),
}


def arm_pose(name: str, arm: str) -> list[float]:
    """Joint positions of the named pose for ``arm``."""
    right = _RIGHT_POSES[name]
    if arm == "right":
        return list(right)
    return [m * v for m, v in zip(_MIRROR, right)]


def arm_pose_map(name: str) -> dict[str, float]:
    """Joint name -> position of the named pose for both arms."""
    out: dict[str, float] = {}
    for arm in ARMS:
        out.update(zip(arm_joint_names(arm), arm_pose(name, arm)))
    return out
