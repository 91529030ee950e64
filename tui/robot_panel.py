"""The robot panel: grippers, last arm and object, executing or idle."""

from __future__ import annotations

from rich.table import Table
from rich.text import Text
from textual.widgets import Static

from tui.world import ARMS, WorldView

_GRIPPER_STYLES = {"open": "green", "closed": "yellow", "holding": "bold magenta"}


class RobotPanel(Static):
    """The situated robot state as the executor reports it, refined by live gripper readings."""

    def show(self, world: WorldView) -> None:
        robot = world.robot
        table = Table.grid(padding=(0, 1))
        table.add_column(style="dim", no_wrap=True)
        table.add_column()
        if not robot and not world.grippers:
            self.update(Text("no robot state yet (executor and sim not heard from)", style="dim"))
            return
        states = robot.get("grippers") or {}
        for arm in ARMS:
            state = str(states.get(arm) or _state_from_sim(world.grippers.get(arm)) or "?")
            reading = world.grippers.get(arm) or {}
            width = reading.get("width")
            detail = f" {float(width) * 100:.1f} cm" if isinstance(width, (int, float)) else ""
            table.add_row(f"{arm} gripper", Text(state, style=_GRIPPER_STYLES.get(state, "")) + Text(detail, style="dim"))
        table.add_row("last arm", str(robot.get("last_arm") or "—"))
        last_object = robot.get("last_object")
        named = last_object in world.descriptions
        table.add_row("last object", world.name_of(last_object) + (f" ({last_object})" if named else ""))
        executing = bool(robot.get("executing"))
        table.add_row("robot", Text("executing", style="bold yellow") if executing else Text("idle", style="green"))
        self.update(table)


def _state_from_sim(reading: dict | None) -> str | None:
    """A gripper word from the simulator's reading, used until the executor reports one."""
    if not reading:
        return None
    if reading.get("holding"):
        return "holding"
    width = reading.get("width")
    if isinstance(width, (int, float)):
        return "open" if width > 0.01 else "closed"
    return None
