"""``hfpbd bench skills`` without the simulator: the tables it draws have what each skill needs, and its figures."""

from __future__ import annotations

import numpy as np
import pytest

from hfpbd.bench_skills import KINDS, Outcome, draw_skill, report, table_for

pytestmark = pytest.mark.unit


def test_every_kind_is_drawn_and_each_table_has_a_landmark_that_fits() -> None:
    seen = set()
    for seed in range(40):
        rng = np.random.default_rng(seed)
        skill = draw_skill(rng)
        seen.add(skill.kind)
        scene, landmark = table_for(rng, skill)
        carried = scene["objects"][0]
        assert carried["type"] in ("cup", "box")
        if skill.kind == "shift":
            assert landmark is None and skill.direction is not None
            continue
        other = next(o for o in scene["objects"] if o["id"] == landmark)
        assert other["id"] != carried["id"]
        if skill.kind in ("serve", "stack"):
            assert other["type"] == ("plate" if skill.kind == "serve" else "box")
            assert other["size"][0] >= carried["size"][0] and skill.relation == "on_top_of"
    assert seen == set(KINDS)


def test_the_figures_count_refusals_apart_and_show_silent_failures(capsys: pytest.CaptureFixture[str]) -> None:
    report(
        [
            Outcome("serve", "achieved", "achieved", "on it"),
            Outcome("serve", "achieved", "refused", "I can't reach the plate."),
            Outcome("stack", "achieved", "silent", "obj0 is not over obj2"),
            Outcome("shift", "refused", "", "teaching pick_up: too wide"),
        ],
        "seeds 0-3",
    )
    out = capsys.readouterr().out
    assert out.startswith("\nseeds 0-3\n")
    assert "all: 4 skills, 3 taught and used; 1/2 uses not refused achieved (50.0%), 1 refused" in out
    assert "0 failures the robot reported, 1 silent" in out
    assert "  use silent (stack): obj0 is not over obj2" in out and "  teaching refused (shift)" in out
