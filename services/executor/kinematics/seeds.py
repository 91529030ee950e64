"""The IK seed table: random arm configurations indexed by where they put the tool frame.

Damped least-squares IK converges only from a nearby start, and random
restarts are too slow for a reachability map of every object × relation ×
arm in under a second. At start-up a few ten thousand random arm
configurations are indexed by their tool frame (position + approach and
finger axes, in the torso's frame so it holds at any torso height); a
target is solved from its nearest neighbours in that table.
"""

from __future__ import annotations

import numpy as np
from mplib.pymp.kinematics.pinocchio import PinocchioModel
from scipy.spatial import cKDTree

from services.executor.geometry import rotation_of

SEED_COUNT = 24000
NEIGHBOURS = 5
APPROACH_WEIGHT, FINGER_WEIGHT = 0.2, 0.1  # metres per unit axis difference in the seed index


def _features(position: np.ndarray, approach: np.ndarray, fingers: np.ndarray) -> np.ndarray:
    return np.concatenate([position, APPROACH_WEIGHT * approach, FINGER_WEIGHT * fingers], axis=-1)


class SeedTable:
    """``count`` arm configurations drawn within ``lo``..``hi`` (seeded), and a k-d tree of their tool frames."""

    def __init__(
        self,
        model: PinocchioModel,
        link: int,
        arm_idx: np.ndarray,
        joints: int,
        lo: np.ndarray,
        hi: np.ndarray,
        count: int,
        rng_seed: int,
    ) -> None:
        rng = np.random.default_rng(rng_seed)
        samples = rng.uniform(lo, hi, size=(count, 7))
        base = np.zeros(joints)
        features = np.empty((count, 9))
        for k, arm_q in enumerate(samples):
            base[arm_idx] = arm_q
            model.compute_forward_kinematics(base)
            matrix = model.get_link_pose(link).to_transformation_matrix()
            features[k] = _features(matrix[:3, 3], matrix[:3, 0], matrix[:3, 1])
        self._seed_q = samples
        self._seed_tree = cKDTree(features)

    def near(self, pose: np.ndarray, torso: float, k: int) -> list[np.ndarray]:
        """The ``k`` configurations whose tool frames lie nearest ``pose`` with the torso at ``torso``."""
        if k <= 0:
            return []
        rot = rotation_of(pose).as_matrix()
        position = np.asarray(pose[:3], float) - [0.0, 0.0, torso]
        _, rows = self._seed_tree.query(_features(position, rot[:, 0], rot[:, 1]), k=k)
        return [self._seed_q[r] for r in np.atleast_1d(rows)]
