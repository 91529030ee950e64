"""``python -m hfpbd.reach_figure [OUT]``: draw where each arm can pick up and place a cup and a box.

The same checks as the reachability map (IK with collisions, the table in
the world) over a grid of the table, for an object alone on it, at the
working torso height and, where that fails, at the lower heights the
executor moves the torso to (``services.executor.torso.HEIGHTS``): "pick"
is some grasp whose pre-grasp and grasp have solutions; "place" is some
release of that object held in the hand (as the pick-up at the middle of
its side of the table grasped it) straight down there, at any of the
headings the hand may turn it to. Written to ``docs/reach.png`` by default.
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from services.executor import geometry as geo
from services.executor import targets, torso
from services.executor.geometry import Box
from services.executor.kinematics import ArmKinematics
from services.executor.planning_scene import seen
from services.executor.reach import can_pick
from services.executor.scene import Scene, measured
from services.sim.layout import TABLE_TOP_Z, TABLE_X, TABLE_Y, table_truth
from shared.contract import ARMS
from shared.messages import PerceivedObject
from shared.robot import ROBOT

OBJECTS = {"cup": (0.07, 0.07, 0.10), "box": (0.06, 0.06, 0.06)}
STEP = 0.04
HEIGHTS = sorted(torso.HEIGHTS, reverse=True)  # the working height (fully up) first
LOWER_ONLY = 0.5  # a cell's shade where only a lower torso reaches
OUT = Path(__file__).resolve().parents[1] / "docs" / "reach.png"


def _object(kind: str, x: float, y: float) -> PerceivedObject:
    size = OBJECTS[kind]
    return PerceivedObject(id="o", color="red", type=kind, position=(x, y, TABLE_TOP_Z + size[2] / 2), size=size)


def _snapshot(*objects: PerceivedObject, torso: float = ROBOT.working_torso):
    scene = Scene()
    scene.update_objects(list(objects), table_truth())
    scene.update_robot(measured({ROBOT.torso_joint: torso, **ROBOT.arm_pose_map("side")}))
    return scene.snapshot()


def _held(kin: ArmKinematics, kind: str) -> targets.Held | None:
    """The object as held after a pick-up at the middle of this arm's side of the table."""
    obj = _object(kind, 0.55, -0.15 if kin.arm == "right" else 0.15)
    snap = _snapshot(obj)
    kin.use(seen(snap, kin.arm, None))
    kin.allow_touching("o", True)
    try:
        for grasp in targets.grasps(obj, snap.near_edge):
            q = kin.ik(grasp.grasp)
            if q is not None:
                held = targets.held_in_hand("o", snap.box("o"), kin.fk(q), snap.table_z)
                return _moved(held, grasp.lift[:3] - grasp.grasp[:3])
    finally:
        kin.allow_touching("o", False)
    return None


def _moved(held: targets.Held, shift: np.ndarray) -> targets.Held:
    """The held object and the hand holding it, both moved by ``shift``."""
    tool = np.concatenate([held.tool_pose[:3] + shift, held.tool_pose[3:]])
    return targets.Held(held.object_id, Box(held.box.center + shift, held.box.size), tool)


def grids(kin: ArmKinematics, kind: str, xs: np.ndarray, ys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per cell, for a pick-up and a place: 1 at the working torso height, LOWER_ONLY only lower, else 0."""
    pick, place = np.zeros((len(xs), len(ys))), np.zeros((len(xs), len(ys)))
    held = _held(kin, kind)
    for i, x in enumerate(xs):
        for j, y in enumerate(ys):
            obj = _object(kind, x, y)
            for height in HEIGHTS:
                shade = 1.0 if height == ROBOT.working_torso else LOWER_ONLY
                if not pick[i, j]:
                    snap = _snapshot(obj, torso=height)
                    kin.use(seen(snap, kin.arm, None))
                    pick[i, j] = shade * can_pick(kin, obj, snap.near_edge)
                if held is not None and not place[i, j]:
                    kin.use(seen(_snapshot(torso=height), kin.arm, None))
                    moved = _moved(held, np.array([x - held.box.center[0], y - held.box.center[1], 0.0]))
                    below = geo.table_release_center(moved.box.center, moved.box.size, TABLE_TOP_Z)
                    releases = geo.carry_poses(moved.tool_pose, moved.box.center, [below], targets.CARRY_YAWS)
                    place[i, j] = shade * (kin.first_reachable(releases) is not None)
    return pick, place


def _picture(right: np.ndarray, left: np.ndarray) -> np.ndarray:
    """RGB per cell: red where only the right arm reaches, blue only the left, white both; each darker where
    a lowered torso is needed (for both arms: where either needs it)."""
    picture = np.zeros((*right.shape, 3))
    both = (right > 0) & (left > 0)
    picture[..., 0] = np.where(both, 0.0, right)
    picture[..., 2] = np.where(both, 0.0, left)
    picture[both] = np.minimum(right, left)[both][:, None]
    return picture


def main(argv: list[str] | None = None) -> int:
    out = Path((argv or sys.argv[1:] or [str(OUT)])[0])
    xs = np.arange(TABLE_X[0] + STEP / 2, 1.0, STEP)
    ys = np.arange(-0.6, 0.6 + 1e-9, STEP)
    arms = {arm: ArmKinematics(arm) for arm in ARMS}
    figure, axes = plt.subplots(len(OBJECTS), 2, figsize=(10, 8), sharex=True, sharey=True)
    for row, kind in enumerate(OBJECTS):
        reached = {arm: grids(arms[arm], kind, xs, ys) for arm in ARMS}
        for col, what in enumerate(("pick up", "place")):
            ax = axes[row][col]
            ax.imshow(
                _picture(reached["right"][col], reached["left"][col]),
                origin="lower",
                extent=(ys[0] - STEP / 2, ys[-1] + STEP / 2, xs[0] - STEP / 2, xs[-1] + STEP / 2),
            )
            ax.set_title(f"{what} a {kind} (red: right arm, blue: left, white: both; dark: torso lowered)", fontsize=9)
            ax.invert_xaxis()
            ax.set_xlabel("y (m, left is +)")
            ax.set_ylabel("x (m, forward)")
    heights = ", ".join(f"{h:.2f}" for h in HEIGHTS[1:])
    figure.suptitle(
        f"Reach on the table, torso at {ROBOT.working_torso:.2f} m or lowered to {heights} m"
        f" (table y {TABLE_Y[0]}–{TABLE_Y[1]} m)"
    )
    figure.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(out, dpi=90)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
