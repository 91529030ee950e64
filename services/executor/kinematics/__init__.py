"""Inverse kinematics and collision-aware motion planning for one PR2 arm (mplib), in layers of one job each.

* :mod:`.scene`: the planning scene as a value (joints, obstacles, what
  the hand carries), given to the model with ``use``.
* :mod:`.model`: the collision world a scene is given to, and the
  collision checks.
* :mod:`.seeds` and :mod:`.ik`: seeded IK (a table of random
  configurations indexed by tool frame, solved from the nearest).
* :mod:`.lines`: straight tool lines (approaches, descents, lifts,
  presses), each returning the path or what blocked it.
* :mod:`.planner`: planned moves between joint states (joint-space lines,
  then RRTConnect).
* :mod:`.timing`: time parameterisation by kind of move.

:class:`ArmKinematics` is all of them on one arm's model, so a check made
by one layer runs against the scene last used (the model is not
thread-safe: one instance per thread).
"""

from __future__ import annotations

from services.executor.kinematics.lines import CONTACT_STEP, MIN_LEAD, ContactMove
from services.executor.kinematics.model import PREFIX, joint_names
from services.executor.kinematics.planner import PLANNING_SLICE, PLANNING_TRIES, ArmPlanner
from services.executor.kinematics.timing import CAREFUL_ACCEL, CAREFUL_SPEED, Trajectory

__all__ = [
    "CAREFUL_ACCEL",
    "CAREFUL_SPEED",
    "CONTACT_STEP",
    "MIN_LEAD",
    "PLANNING_SLICE",
    "PLANNING_TRIES",
    "PREFIX",
    "ArmKinematics",
    "ContactMove",
    "Trajectory",
    "joint_names",
]


class ArmKinematics(ArmPlanner):
    """IK, collision checks and planning for one arm. Not thread-safe: one instance per thread."""
