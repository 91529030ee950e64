"""Seeded inverse kinematics for one arm, and what a pose's solutions would hit.

A target is solved from the given seeds, then the current configuration,
then its nearest neighbours in the seed table
(:mod:`services.executor.kinematics.seeds`).
"""

from __future__ import annotations

import numpy as np

from services.executor.kinematics.model import HELD_PREFIX, PREFIX, ROLL_JOINTS, ArmModel, _part_name, _to_pose
from services.executor.kinematics.seeds import NEIGHBOURS

IK_ITERATIONS = 25  # Newton steps per start: a start that converges does so in about ten
ARM_REACH = 1.0  # metres from the shoulder pan axis to the farthest tool position (0.1 + 0.4 + 0.321 + 0.18)
STEER_NUDGE = 0.1  # rad the elbow is swung to look for solutions with more room to the joint limits
STEER_JUMP = 0.15  # rad: the most any joint may move between two poses of a contact move


def _nudged(arm_q: np.ndarray) -> list[np.ndarray]:
    """Starts beside ``arm_q`` with the elbow swung a little (upper-arm roll, shoulder pan)."""
    out = []
    for joint, delta in ((2, STEER_NUDGE), (2, -STEER_NUDGE), (0, STEER_NUDGE), (0, -STEER_NUDGE)):
        q = arm_q.copy()
        q[joint] += delta
        out.append(q)
    return out


class ArmIK(ArmModel):
    """IK on the arm's planning model."""

    # -- inverse kinematics ---------------------------------------------------------
    def ik(
        self,
        pose: np.ndarray,
        *,
        seeds: list[np.ndarray] | None = None,
        check_collisions: bool = True,
        neighbours: int = NEIGHBOURS,
    ) -> np.ndarray | None:
        """Arm joints putting the tool frame at ``pose``, or None.

        Tries the given seeds, then the current joints, then the nearest
        table entries; a solution counts only within joint limits and, when
        ``check_collisions``, without touching anything. The solver runs
        unbounded (bounding it mid-iteration traps it at the limits far more
        often) and the answer is checked against the limits afterwards.
        """
        if np.linalg.norm(np.asarray(pose[:3], float) - self.shoulder()) > ARM_REACH:
            return None
        goal = _to_pose(pose)
        starts = list(seeds or []) + [self.arm_q] + self._seeds.near(pose, self.qpos[self.torso_idx], neighbours)
        for start in starts:
            q, ok, _ = self.model.compute_IK_CLIK(
                self.link, goal, self.full(start), self._ik_mask, eps=1e-4, max_iter=IK_ITERATIONS, dt=1.0
            )
            if not ok:
                continue
            arm_q = self._wrapped(q[self.arm_idx])
            if not self.within_limits(arm_q):
                continue
            if check_collisions and self.collisions(arm_q):
                continue
            return self._unwound(arm_q)
        return None

    def _wrapped(self, arm_q: np.ndarray) -> np.ndarray:
        """Roll joints brought into one turn (the solver lets them wander past their limits)."""
        out = arm_q.copy()
        for j in ROLL_JOINTS:
            out[j] = (out[j] + np.pi) % (2 * np.pi) - np.pi
        return out

    def _unwound(self, arm_q: np.ndarray) -> np.ndarray:
        """Roll joints turned by whole turns to stay nearest the current ones (no needless spins)."""
        out = arm_q.copy()
        current = self.arm_q
        for j in ROLL_JOINTS:
            lo, hi = self.limits[self.arm_idx[j]]
            best = out[j]
            for turn in (-2 * np.pi, 2 * np.pi):
                candidate = arm_q[j] + turn
                if lo <= candidate <= hi and abs(candidate - current[j]) < abs(best - current[j]):
                    best = candidate
            out[j] = best
        return out

    def _turned_towards(self, arm_q: np.ndarray, reference: np.ndarray) -> np.ndarray:
        """Roll joints turned by whole turns to lie nearest ``reference`` (the previous waypoint of a line)."""
        out = arm_q.copy()
        for j in ROLL_JOINTS:
            lo, hi = self.limits[self.arm_idx[j]]
            for turn in (-2 * np.pi, 2 * np.pi):
                candidate = out[j] + turn
                if lo <= candidate <= hi and abs(candidate - reference[j]) < abs(out[j] - reference[j]):
                    out[j] = candidate
        return out

    def turn_variants(self, arm_q: np.ndarray) -> list[np.ndarray]:
        """``arm_q`` and the same posture with the roll joints turned by whole turns (within the limits).

        They put the tool in the same place, but a straight line from one may
        run a roll joint into its limit where from another it does not; the
        ones with the rolls nearest the middle of their range come first.
        """
        out = [arm_q]
        for j in ROLL_JOINTS:
            lo, hi = self.limits[self.arm_idx[j]]
            for q in list(out):
                for turn in (-2 * np.pi, 2 * np.pi):
                    if lo <= q[j] + turn <= hi:
                        variant = q.copy()
                        variant[j] += turn
                        out.append(variant)
        return sorted(out, key=lambda q: sum(abs(q[j]) for j in ROLL_JOINTS))

    def first_reachable(self, poses: list[np.ndarray], **kw: object) -> tuple[int, np.ndarray] | None:
        """Index and joints of the first pose in ``poses`` with an IK solution."""
        for i, pose in enumerate(poses):
            q = self.ik(pose, **kw)  # type: ignore[arg-type]
            if q is not None:
                return i, q
        return None

    def blockers(self, poses: list[np.ndarray]) -> set[str] | None:
        """Why none of ``poses`` is reachable: what the IK solutions would hit (None: out of reach).

        Names are obstacle names or ``"right arm"`` / ``"left arm"`` / ``"body"``
        for the robot itself, so a refusal can say what is in the way.
        """
        hits: set[str] = set()
        for pose in poses:
            arm_q = self.ik(pose, check_collisions=False)
            if arm_q is None:
                continue
            for pair in self.collisions(arm_q):
                other = [n for n in pair if not n.startswith((f"{PREFIX[self.arm]}_", HELD_PREFIX))]
                hits.update(_part_name(n) for n in other)
        return hits or None

    def _steered_ik(self, pose: np.ndarray, previous: np.ndarray) -> np.ndarray | None:
        """The solution near ``previous`` that keeps the joints farthest from their limits.

        The solver follows the least-squares direction, which on a long line
        close to the body runs the wrist flex into its limit while the
        7-joint arm could still reach on by swinging its elbow. Starting
        also from ``previous`` with the elbow swung a little (shoulder pan,
        upper-arm roll) and keeping the solution with the most room lets a
        hand that must not leave the line (it presses on an object) go on.
        """
        best, room = None, -np.inf
        for seed in (previous, *_nudged(previous)):
            q = self.ik(pose, seeds=[seed], check_collisions=False, neighbours=0)
            if q is not None:
                q = self._turned_towards(q, previous)
            if q is None or np.max(np.abs(q - previous)) > STEER_JUMP:
                continue
            margin = self._limit_room(q)
            if margin > room + 1e-3:
                best, room = q, margin
        return best

    def _limit_room(self, arm_q: np.ndarray) -> float:
        """Smallest distance to a joint limit, as a share of the joint's range (roll joints excluded)."""
        lim = self.limits[self.arm_idx]
        share = np.minimum(arm_q - lim[:, 0], lim[:, 1] - arm_q) / (lim[:, 1] - lim[:, 0])
        return float(np.delete(share, list(ROLL_JOINTS)).min())
