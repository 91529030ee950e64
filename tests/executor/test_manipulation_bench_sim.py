"""A short seeded subset of ``hfpbd bench manipulation`` on the real sim, perception and executor."""

from __future__ import annotations

import pytest

from hfpbd.bench_manipulation import Driver, run_task
from tests.executor.stack import Stack

pytestmark = pytest.mark.slow

SEEDS = (1, 2)  # seed 1: put it next to an object; seed 2: put it down on the table


@pytest.mark.parametrize("seed", SEEDS)
def test_a_random_task_is_achieved_and_replayed_or_refused_with_a_reason(stack: Stack, seed: int) -> None:
    outcome = run_task(Driver(stack.hub), seed)
    assert outcome.result != "failed", f"{outcome.kind}: {outcome.reason}"
    if outcome.result == "refused":
        assert outcome.reason.split(": ", 1)[1], "refused without a reason"
    else:
        assert outcome.replay == "achieved", f"{outcome.kind} replay: {outcome.replay_reason}"
