"""The speech gate: sounds that are no speech are dropped before decoding; speech, clean or in noise, passes."""

from __future__ import annotations

import numpy as np
import pytest

from services.speech import espeak, sounds
from services.speech.audio import RATE, silence
from services.speech.gate import judge

pytestmark = pytest.mark.skipif(not espeak.available(), reason="espeak-ng is not installed")


@pytest.mark.parametrize("kind", ["white noise", "pink noise", "brown noise", "hum", "tones", "chords", "coughs"])
@pytest.mark.parametrize("seed", [1, 2])
def test_sounds_that_are_no_speech_are_dropped(kind: str, seed: int) -> None:
    verdict = judge(np.concatenate([silence(0.3), sounds.sound(kind, seed, 2.0), silence(0.3)]))
    assert not verdict.speech and verdict.reason


@pytest.mark.parametrize("noise", [None, ("pink noise", 20.0), ("white noise", 25.0), ("babble", 15.0)])
@pytest.mark.parametrize(("text", "voice"), [("stop", "en-gb"), ("move your right hand up", "en-us")])
def test_commands_pass_clean_and_in_noise(text: str, voice: str, noise: tuple[str, float] | None) -> None:
    pcm = np.concatenate([silence(0.3), espeak.synthesise(text, voice, 150), silence(0.3)])
    if noise is not None:
        pcm = sounds.mixed(pcm, sounds.sound(noise[0], 7, len(pcm) / RATE), noise[1])
    assert judge(pcm).speech


def test_a_click_is_too_short_for_a_word() -> None:
    assert not judge(sounds.sound("coughs", 3, 0.05)).speech
