"""Turn a head-camera frame into the organised point cloud that ``sim/cloud`` carries.

Why organised (H × W with NaN holes) rather than a list of points: the
pixel grid keeps neighbourhoods for free (perception can segment in image
space) and the message size never depends on the scene. Like a Kinect,
nothing nearer than 0.4 m or farther than 4.5 m returns a point.
"""

from __future__ import annotations

import numpy as np

from services.sim.world import Capture
from shared.robot import ROBOT


def cloud_arrays(capture: Capture) -> tuple[np.ndarray, np.ndarray]:
    """(H, W, 3) float32 xyz in the base frame (NaN = no return) and (H, W, 3) uint8 rgb."""
    position = capture.position
    camera_xyz = position[..., :3]
    distance = -camera_xyz[..., 2]  # OpenGL camera looks along -z
    valid = (position[..., 3] < 1.0) & (distance >= ROBOT.camera.near) & (distance <= ROBOT.camera.far)
    rotation = capture.model_matrix[:3, :3].astype(np.float32)
    translation = capture.model_matrix[:3, 3].astype(np.float32)
    xyz = camera_xyz @ rotation.T + translation
    xyz[~valid] = np.nan
    rgb = (np.clip(capture.color[..., :3], 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)
    return xyz.astype(np.float32, copy=False), rgb


def cloud_message(capture: Capture, stamp: float) -> dict:
    xyz, rgb = cloud_arrays(capture)
    height, width = xyz.shape[:2]
    return {
        "stamp": stamp,
        "sim_time": capture.sim_time,
        "scene": capture.scene,
        "scene_generation": capture.scene_generation,
        "xyz": xyz,
        "rgb": rgb,
        "camera_pose": capture.camera_pose,
        "width": width,
        "height": height,
        "frame": "base",
    }
