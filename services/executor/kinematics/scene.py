"""The planning scene: what one arm's checks and plans are made against, as one value handed forward.

A check asks "from these joints, among these obstacles, carrying this,
is the way clear?". The scene is that question's world: the robot's joints
(the other arm and the torso included), the boxes around it, and what the
hand carries. It is built from what the robot perceives
(:func:`services.executor.planning_scene.seen`), or from another scene
("as it will be once the cup is lifted"), and given to the arm's model with
:meth:`~services.executor.kinematics.model.ArmModel.use`, so what a check
ran against is one value a reader can follow, not state set here and there.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from services.executor.geometry import Box


@dataclass(frozen=True)
class Carried:
    """An object in the hand: its box with the tool at ``tool_pose`` (it moves and turns with the hand)."""

    object_id: str
    box: Box
    tool_pose: np.ndarray = field(compare=False)


@dataclass(frozen=True)
class PlanningScene:
    """Joints by name (those not named stay as they are), obstacles by name, and what the hand carries."""

    joints: Mapping[str, float] = field(default_factory=dict)
    obstacles: Mapping[str, Box] = field(default_factory=dict)
    carried: Carried | None = None
