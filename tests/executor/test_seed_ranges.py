"""A table benchmark's two ranges of seeds: the usual one and a fresh one, run in turns."""

from __future__ import annotations

import pytest

from hfpbd import seed_ranges

pytestmark = pytest.mark.unit


def test_the_fresh_range_is_drawn_far_from_the_usual_one_unless_named() -> None:
    (usual_title, usual), (fresh_title, fresh) = seed_ranges.ranges(3, 0, None)
    assert usual == [0, 1, 2] and usual_title == "seeds 0-2"
    assert seed_ranges.FRESH_SEEDS[0] <= fresh[0] < seed_ranges.FRESH_SEEDS[1] and len(fresh) == 3
    assert f"--fresh {fresh[0]}" in fresh_title  # how to run the same fresh tables again
    assert seed_ranges.ranges(2, 5, 700)[1][1] == [700, 701]


def test_the_ranges_take_turns_and_a_run_cut_short_keeps_what_is_done(capsys: pytest.CaptureFixture[str]) -> None:
    order: list[int] = []

    def run(seed: int) -> int:
        if seed == 12:
            raise KeyboardInterrupt
        order.append(seed)
        return seed * 2

    results = seed_ranges.run_in_turns([("a", [1, 2, 3]), ("b", [11, 12, 13])], run, str)
    assert order == [1, 11, 2]
    assert results == [("a", [2, 4]), ("b", [22])]
    assert "seed 11: 22" in capsys.readouterr().out
