"""Tell everyone the moment stopped joints come to rest, not at the next state tick.

Why: ``sim/state`` goes out at a steady rate, so a stop would otherwise be
seen up to one period late — most of what a person waits for after the stop
key. Joints told to stop are watched each physics step; the step on which
all of them move slower than :data:`AT_REST`, a state is published at once.
"""

from __future__ import annotations

import numpy as np

AT_REST = 0.02  # rad/s (or m/s for the torso): a joint slower than this has stopped
WATCH_FOR = 1.0  # s of simulated time: a joint still moving after this is left to the steady ticks


class Halting:
    """The joint indices told to stop and not yet at rest, with the simulated time they were told."""

    def __init__(self) -> None:
        self._indices: set[int] = set()
        self._since = 0.0

    def stopped(self, indices: list[int], sim_time: float) -> None:
        self._indices.update(indices)
        self._since = sim_time

    @property
    def watching(self) -> bool:
        return bool(self._indices)

    def came_to_rest(self, qvel: np.ndarray, sim_time: float) -> bool:
        """True once, on the step every watched joint is at rest (or the watch gives up)."""
        if sim_time - self._since < WATCH_FOR and np.max(np.abs(qvel[sorted(self._indices)])) >= AT_REST:
            return False
        self._indices.clear()
        return True
