"""The speech benchmark counts what the service would act on, the stops it sends early included."""

from __future__ import annotations

import numpy as np
import pytest

from services.speech import espeak
from services.speech.audio import silence
from services.speech.bench import NON_SPEECH_SCENE, Listener, early_stops, meaning, outcome
from services.speech.corpus import SCENES, STATES

pytestmark = pytest.mark.skipif(not espeak.available(), reason="espeak-ng is not installed")


def test_an_offer_withdrawn_later_counts_only_when_the_service_would_have_sent_a_stop_from_it():
    listener = Listener("core")
    world = {"objects": SCENES[NON_SPEECH_SCENE][0], "robot": STATES["right"]}
    said = [
        np.concatenate([silence(0.3), espeak.synthesise(text, "en-us", 150)]) for text in ("stop", "open your hand")
    ]
    heard = early_stops(listener, world, said, "fillers")
    assert len(heard) == 1
    assert heard[0].choice is not None and meaning(heard[0].choice.reading.result) == {"procedure": "stop", "args": {}}
    assert outcome(heard[0]) == "acted" and heard[0].seconds == 0.0  # a stop acted on, in no extra audio
