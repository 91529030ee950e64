"""The robot panel: grippers, last arm and object, executing or idle."""

from __future__ import annotations

from rich.table import Table
from rich.text import Text
from textual.widgets import Static

from shared.messages import Gripper
from tui.world import ARMS, WorldView

_GRIPPER_STYLES = {"open": "green", "closed": "yellow", "holding": "bold magenta"}


class RobotPanel(Static):
    """The situated robot state as the executor reports it, refined by live gripper readings."""

    def __init__(self, **kwargs: object) -> None:
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.fields: dict[str, str] = {}  # what the panel shows, as plain text

    def show(self, world: WorldView) -> None:
        robot = world.robot
        if robot is None and not world.grippers:
            self.fields = {}
            self.update(Text("no robot state yet (executor and sim not heard from)", style="dim"))
            return
        rows: list[tuple[str, Text]] = []
        states = robot.grippers if robot is not None else {}
        for arm in ARMS:
            reading = world.grippers.get(arm)
            state = str(states.get(arm) or _state_from_sim(reading) or "?")
            detail = f" {reading.width * 100:.1f} cm" if reading is not None else ""
            shown = Text(state, style=_GRIPPER_STYLES.get(state, "")) + Text(detail, style="dim")
            rows.append((f"{arm} gripper", shown))
        rows.append(("last arm", Text(str(robot.last_arm if robot is not None and robot.last_arm else "—"))))
        last_object = robot.last_object if robot is not None else None
        named = last_object in world.descriptions
        rows.append(("last object", Text(world.name_of(last_object) + (f" ({last_object})" if named else ""))))
        if robot is not None and robot.executing:
            rows.append(("robot", Text("executing the action", style="bold yellow")))
        elif robot is not None and robot.busy:
            rows.append(("robot", Text("moving", style="yellow")))
        else:
            rows.append(("robot", Text("idle", style="green")))
        table = Table.grid(padding=(0, 1))
        table.add_column(style="dim", no_wrap=True)
        table.add_column()
        for label, value in rows:
            table.add_row(label, value)
        self.fields = {label: value.plain for label, value in rows}
        self.update(table)


def _state_from_sim(reading: Gripper | None) -> str | None:
    """A gripper word from the simulator's reading, used until the executor reports one."""
    if reading is None:
        return None
    if reading.holding:
        return "holding"
    return "open" if reading.width > 0.01 else "closed"
