"""The README's first-minutes walkthrough, run exactly as written, judged from the simulator's ground truth.

The table in README.md under "Your first minutes" is what a new user types
on the default table and what the robot answers. This test sends each line
through the real services as the TUI does, requires the robot to answer in
the words the README shows, and checks where the cups really are after each
step: the README must never promise what the robot does not do. The robot
names objects afresh by what singles them out at that moment ("the rightmost
cup" may be "the farthest cup" once it stands on the plate), so descriptions
are compared by the kind of object they name; which cup it really was is
what the ground truth judges.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from hfpbd.manipulation_judge import placed
from hfpbd.tasks.runner import TaskRunner

pytestmark = [pytest.mark.slow, pytest.mark.timeout(900)]

README = Path(__file__).resolve().parents[2] / "README.md"
HEADING = "## Your first minutes"
RED_CUP, BLUE_CUP, BOX, PLATE = "obj0", "obj1", "obj2", "obj3"  # the default scene's ids (services/sim/scenes)
DESCRIPTION = re.compile(r"\bthe (?:[a-z]+ )*?(cup|box|plate|bowl|object)\b")
LIFTED = 0.05  # metres: a pick-up (or a lift) raises the cup at least this far above where it was

# what each row of the walkthrough leaves a cup doing: lifted, or placed (relation, landmark)
OUTCOMES: list[tuple[str, str, str | None]] = [
    (RED_CUP, "lifted", None),
    (RED_CUP, "next_to", BLUE_CUP),
    (RED_CUP, "lifted", None),
    (RED_CUP, "on_top_of", PLATE),
    (BLUE_CUP, "lifted", None),
    (BLUE_CUP, "lifted", None),
    (BLUE_CUP, "down", None),
    (BLUE_CUP, "lifted", None),
    (BLUE_CUP, "on_top_of", BOX),
]


def walkthrough() -> list[tuple[str, str]]:
    """(what you type, what the robot says) for each row of the README's walkthrough table."""
    text = README.read_text(encoding="utf-8")
    section = text.split(HEADING, 1)[1].split("\n## ", 1)[0]
    rows = [line for line in section.splitlines() if line.startswith("| ") and not line.startswith("| You")]
    pairs = []
    for row in rows:
        cells = [cell.strip() for cell in row.strip().strip("|").split("|")]
        if set("".join(cells)) <= set("-: "):
            continue  # the header's rule
        typed, answer = (re.sub(r"^`|`$", "", cell) for cell in cells)
        pairs.append((typed, answer))
    return pairs


def by_kind(sentence: str) -> str:
    """The sentence with each object description cut down to its kind ("the rightmost cup" -> "the cup")."""
    return DESCRIPTION.sub(r"the \1", sentence)


def test_the_readme_walkthrough_is_the_one_judged() -> None:
    assert len(walkthrough()) == len(OUTCOMES), "README walkthrough rows and this test's outcomes differ in number"


def test_the_first_minutes_happen_as_the_readme_says(runner: TaskRunner) -> None:
    runner.load_scene("default")
    for (typed, answer), (cup, outcome, landmark) in zip(walkthrough(), OUTCOMES, strict=True):
        before = np.asarray(runner.watch.truth[cup].position, dtype=float)
        step = runner.say(typed)
        said = " ".join(line.split(": ", 1)[1] for line in step.said)
        assert step.ok, f"{typed!r}: {step.problem}"
        assert by_kind(said) == by_kind(answer), f"{typed!r}: the robot said {said!r}, the README says {answer!r}"
        if outcome == "lifted":
            now = np.asarray(runner.watch.truth[cup].position, dtype=float)
            assert now[2] > before[2] + LIFTED, f"{typed!r}: {cup} is not lifted (z {before[2]:.3f} → {now[2]:.3f})"
        else:
            verdict = placed(runner.watch.settled(), cup, outcome, landmark)
            assert verdict.success, f"{typed!r}: {verdict.reason}"
