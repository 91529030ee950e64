"""Both arms at once: one time law for the two paths, and a check that the arms never meet on the way.

Each arm's path is planned on its own model, with the other arm where it
stands now; moving both at once is safe only if the two paths, followed at
the same time, keep the arms (and what they hold) apart, so the pair is
checked pose by pose at common instants. Both paths are then timed by one
smooth time law over the same duration — the slower arm's — so they start
together, are at the same share of their way at every instant (two hands
lifting a squeezed box keep it level) and finish together.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from services.executor.kinematics import CAREFUL_ACCEL, CAREFUL_SPEED, PREFIX, ArmKinematics, Trajectory, joint_names

MIN_DURATION = 0.5  # seconds: the shortest joint motion of both arms
CHECKS_PER_SECOND = 40  # instants at which the two moving arms are checked against each other
PEAK_ACCELERATION = 10.0 / np.sqrt(3.0)  # a minimum-jerk motion's peak acceleration, in travel / duration²


def _minimum_jerk(u: np.ndarray) -> np.ndarray:
    return u**3 * (10.0 - 15.0 * u + 6.0 * u**2)


def _time_share(share: np.ndarray) -> np.ndarray:
    """The share of the duration at which a minimum-jerk motion has covered ``share`` of its way."""
    grid = np.linspace(0.0, 1.0, 2001)
    return np.interp(share, _minimum_jerk(grid), grid)


def _way_shares(points: np.ndarray) -> np.ndarray:
    """How far along its way each waypoint lies (0 … 1, strictly increasing).

    Mostly by index — the straight-line paths have their waypoints equally
    spaced along the tool's line, so two hands moving the same distance stay
    level — blended with the joint-space length, so that a planned path with
    uneven waypoints is not hurried over its long segments.
    """
    n = len(points)
    by_index = np.linspace(0.0, 1.0, n)
    lengths = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    by_length = lengths / lengths[-1] if lengths[-1] > 1e-9 else by_index
    return 0.7 * by_index + 0.3 * by_length


def timed_together(paths: Mapping[str, np.ndarray]) -> dict[str, Trajectory]:
    """Timed trajectories for untimed joint paths, sharing one start, one end and one time law.

    The duration is the shortest for which no joint of either arm exceeds
    the planning speed anywhere, nor (by the minimum-jerk law's peak, for
    the joint's whole travel) the planning acceleration — a box held by the
    friction of two hands must not be jerked out of them — and at least
    :data:`MIN_DURATION`.
    """
    shares = {arm: _time_share(_way_shares(p)) if len(p) > 1 else np.zeros(1) for arm, p in paths.items()}
    duration = MIN_DURATION
    for arm, points in paths.items():
        if len(points) < 2:
            continue
        steps = np.abs(np.diff(points, axis=0))
        shortest_by_speed = np.max(steps.max(axis=1) / (CAREFUL_SPEED * np.maximum(np.diff(shares[arm]), 1e-9)))
        shortest_by_acceleration = np.sqrt(PEAK_ACCELERATION * steps.sum(axis=0).max() / CAREFUL_ACCEL)
        duration = max(duration, float(shortest_by_speed), float(shortest_by_acceleration))
    out: dict[str, Trajectory] = {}
    for arm, points in paths.items():
        if len(points) < 2:  # standing still for the other arm's motion
            out[arm] = Trajectory(np.vstack([points[:1], points[:1]]), np.array([0.0, duration]))
        else:
            out[arm] = Trajectory(np.asarray(points, float), shares[arm] * duration)
    return out


def _at(trajectory: Trajectory, t: float) -> np.ndarray:
    points = trajectory.points
    return np.array([np.interp(t, trajectory.times, points[:, j]) for j in range(points.shape[1])])


def _mine(name: str, arm: str, kin: ArmKinematics) -> bool:
    return name.startswith(f"{PREFIX[arm]}_") or (kin.held_body is not None and name == kin.held_body)


def first_clash(kins: Mapping[str, ArmKinematics], trajectories: Mapping[str, Trajectory]) -> float | None:
    """The first instant at which the two arms (or what they hold) would touch each other, or None.

    Each arm's model is posed with the other arm where that one is at the
    same instant; only contacts between the two arms count (a hand's press
    against an object is its plan's business). The models are put back to
    their joints afterwards.
    """
    duration = max(t.duration for t in trajectories.values())
    count = max(2, int(np.ceil(duration * CHECKS_PER_SECOND)) + 1)
    saved = {arm: kin.qpos.copy() for arm, kin in kins.items()}
    try:
        for t in np.linspace(0.0, duration, count):
            poses = {arm: _at(trajectories[arm], t) for arm in trajectories}
            for arm, kin in kins.items():
                other = next(a for a in kins if a != arm)
                kin.set_joints(dict(zip(joint_names(other), poses[other])))
                for a, b in kin.collisions(poses[arm]):
                    if (_mine(a, arm, kin) and b.startswith(f"{PREFIX[other]}_")) or (
                        _mine(b, arm, kin) and a.startswith(f"{PREFIX[other]}_")
                    ):
                        return float(t)
    finally:
        for arm, kin in kins.items():
            kin.qpos = saved[arm]
    return None
