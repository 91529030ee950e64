"""Generated input that is no command (numbers, code, remarks to someone else, questions about other things)
never becomes one: each is refused or asked about. The benchmark draws another seed (``hfpbd bench nlu``)."""

from __future__ import annotations

import pytest

from services.nlu import corpus
from services.nlu.bench import NOT_MEANT_SCENES, NOT_MEANT_SEED, outcome
from services.nlu.corpus.remarks import remarks
from services.nlu.infer import Model
from services.nlu.world import parse_world

pytestmark = pytest.mark.unit
SEED = 29


def test_the_test_and_the_benchmark_draw_different_inputs() -> None:
    assert SEED != NOT_MEANT_SEED and set(remarks(200, SEED)) != set(remarks(200, NOT_MEANT_SEED))


@pytest.mark.parametrize("scene", NOT_MEANT_SCENES)
def test_nothing_that_is_no_command_moves_the_robot(scene: str) -> None:
    scenes, _ = corpus.load()
    model = Model(parse_world(scenes[scene]))
    acted = [text for text in remarks(1000, SEED) if outcome(model.parse(text)) == "acted on"]
    assert acted == []
