"""Fail early, with a clear reason, when SAPIEN cannot render offscreen here.

Setup runs this once: without a working Vulkan device (a GPU driver, or
Mesa >= 24.3 lavapipe on a CPU) the simulator cannot produce point clouds.
"""

from __future__ import annotations

import sys


def main() -> int:
    try:
        import numpy as np
        import sapien

        scene = sapien.Scene()
        scene.add_ground(0)
        scene.set_ambient_light([0.5, 0.5, 0.5])
        builder = scene.create_actor_builder()
        builder.add_box_visual(half_size=[0.1, 0.1, 0.1], material=[1.0, 0.0, 0.0])
        box = builder.build_static(name="box")
        box.set_pose(sapien.Pose([1.0, 0.0, 0.1]))
        camera = scene.add_camera("check", width=64, height=48, fovy=0.8, near=0.05, far=10)
        camera.entity.set_pose(sapien.Pose([0.0, 0.0, 0.3]))
        scene.update_render()
        camera.take_picture()
        depth = camera.get_picture("Position")[..., 2]
        if not np.any(depth < 0):
            print("render check: the camera saw nothing", file=sys.stderr)
            return 1
    except Exception as exc:  # the exact failure is what the person needs to see
        print(
            f"render check failed: SAPIEN cannot render offscreen here ({exc}). "
            "Install a Vulkan driver: Mesa >= 24.3 (mesa-vulkan-drivers from bookworm-backports) "
            "or a GPU driver.",
            file=sys.stderr,
        )
        return 1
    print("render check: SAPIEN renders offscreen")
    return 0


if __name__ == "__main__":
    sys.exit(main())
