"""Where the scene's furniture is: the table the robot works at.

The robot's own facts (joint names, postures, the working torso height,
where the head looks) are in :mod:`shared.robot`; this module holds only the
simulated scene around it. World frame == robot base frame: the robot stands
fixed at the origin, x forward, y left, z up, z = 0 on the floor.
"""

from __future__ import annotations

from shared.messages import Table, TableExtent

TABLE_TOP_Z = 0.72  # a real table (0.72–0.76 m), worked with the torso raised
TABLE_THICKNESS = 0.04
TABLE_X = (0.35, 1.15)  # near and far edge; the near edge clears the base (x ≤ 0.334)
TABLE_Y = (-0.80, 0.80)


def table_truth() -> Table:
    """The table as perception's ``table`` field describes it, every edge seen: for tests and benchmarks
    that feed the executor ground truth instead of a camera's view."""
    return Table(
        height=TABLE_TOP_Z,
        normal=(0.0, 0.0, 1.0),
        outline=[
            (TABLE_X[0], TABLE_Y[0]),
            (TABLE_X[1], TABLE_Y[0]),
            (TABLE_X[1], TABLE_Y[1]),
            (TABLE_X[0], TABLE_Y[1]),
        ],
        extent=TableExtent(x=TABLE_X, y=TABLE_Y),
        edges={"near": TABLE_X[0], "far": TABLE_X[1], "right": TABLE_Y[0], "left": TABLE_Y[1]},
    )
