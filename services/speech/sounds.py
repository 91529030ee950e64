"""Sounds that are not commands, synthesised: what the microphone hears between commands.

Why synthesised: a benchmark and the tests need a large, repeatable set of
non-speech (and of speech that is no command) without shipping recordings.
Each kind imitates one thing a robot's microphone picks up: hiss and hum of
the room, coughs and throat sounds (shaped noise bursts), filler sounds and
laughter (spoken by a synthesiser), tones and chords (a phone, music), a
conversation nearby (off-topic sentences, quiet and overlapping), and the
robot's own voice (its usual phrases at full level). Every generator takes a
seed, so a set is the same on every run.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.signal import lfilter

from services.speech import espeak
from services.speech.audio import RATE

FILLERS = ("um", "umm", "uh", "hmm", "erm", "ah", "oh", "mm hmm", "uh huh", "well")
LAUGHTER = ("ha ha ha", "ha ha", "hehe", "ha ha ha ha")
OFF_TOPIC = (
    "what a lovely day it is today",
    "did you see the game last night",
    "I think the meeting starts at three",
    "could you pass me the salt",
    "we should order some lunch soon",
    "my train was late again this morning",
    "the weather will be better tomorrow",
    "have you finished the report yet",
    "let us go for a walk after work",
    "I left my keys in the car",
)
ROBOT_PHRASES = (
    "I picked up the green box.",
    "Which cup do you mean, the red one or the blue one?",
    "I couldn't make out that command. Please say it again.",
    "All right. What should I do next?",
    "Action two has three steps.",
    "I put the red cup on the plate.",
    "I moved my right hand above the blue cup.",
    "I didn't catch that.",
)


def _level(pcm: np.ndarray, dbfs: float) -> np.ndarray:
    """``pcm`` scaled to an RMS of ``dbfs`` decibels below full scale, as int16."""
    data = np.asarray(pcm, dtype=np.float64)
    rms = float(np.sqrt(np.mean(data**2))) or 1.0
    scaled = data * (32768.0 * 10 ** (dbfs / 20) / rms)
    return np.clip(np.round(scaled), -32768, 32767).astype(np.int16)


def _samples(seconds: float) -> int:
    return int(round(seconds * RATE))


def white(rng: np.random.Generator, seconds: float, dbfs: float = -30.0) -> np.ndarray:
    return _level(rng.normal(size=_samples(seconds)), dbfs)


def pink(rng: np.random.Generator, seconds: float, dbfs: float = -30.0) -> np.ndarray:
    """1/f noise (a fan, air conditioning), from white noise through Kellet's three-pole filter."""
    b = [0.049922035, -0.095993537, 0.050612699, -0.004408786]
    a = [1.0, -2.494956002, 2.017265875, -0.522189400]
    return _level(lfilter(b, a, rng.normal(size=_samples(seconds))), dbfs)


def brown(rng: np.random.Generator, seconds: float, dbfs: float = -30.0) -> np.ndarray:
    """1/f² noise (rumble, traffic)."""
    return _level(lfilter([1.0], [1.0, -0.995], rng.normal(size=_samples(seconds))), dbfs)


def hum(rng: np.random.Generator, seconds: float, dbfs: float = -30.0) -> np.ndarray:
    """Mains hum: 50 or 60 Hz and its harmonics, with a little noise."""
    t = np.arange(_samples(seconds)) / RATE
    base = float(rng.choice([50.0, 60.0]))
    wave = sum(np.sin(2 * np.pi * base * k * t + rng.uniform(0, 6.3)) / k for k in range(1, 8))
    return _level(wave + 0.05 * rng.normal(size=len(t)), dbfs)


def tone(rng: np.random.Generator, seconds: float, dbfs: float = -20.0) -> np.ndarray:
    """Beeps of a phone or a machine: a tone switched on and off."""
    t = np.arange(_samples(seconds)) / RATE
    gate = (np.floor(t / rng.uniform(0.15, 0.5)) % 2 == 0).astype(float)
    return _level(np.sin(2 * np.pi * rng.uniform(400, 2500) * t) * gate + 1e-3 * rng.normal(size=len(t)), dbfs)


def chords(rng: np.random.Generator, seconds: float, dbfs: float = -22.0) -> np.ndarray:
    """Music-like: a sequence of triads of harmonic tones with a decaying envelope."""
    out = np.zeros(_samples(seconds))
    start = 0
    while start < len(out):
        length = min(len(out) - start, _samples(rng.uniform(0.3, 0.8)))
        t = np.arange(length) / RATE
        root = 110.0 * 2 ** (rng.integers(0, 24) / 12)
        note = np.zeros(length)
        for step in (0, 4, 7):
            f = root * 2 ** (step / 12)
            note += sum(np.sin(2 * np.pi * f * k * t) / k**1.5 for k in range(1, 5))
        out[start : start + length] = note * np.exp(-t * rng.uniform(1.5, 4.0))
        start += length
    return _level(out + 1e-3 * rng.normal(size=len(out)), dbfs)


def coughs(rng: np.random.Generator, seconds: float, dbfs: float = -18.0) -> np.ndarray:
    """Coughs and throat clearing: bursts of band-passed noise with a sharp onset and a decay."""
    out = np.zeros(_samples(seconds))
    at = _samples(rng.uniform(0.05, 0.3))
    while at < len(out):
        length = _samples(rng.uniform(0.15, 0.45))
        t = np.arange(length) / RATE
        burst = rng.normal(size=length) * np.exp(-t * rng.uniform(6, 20)) * (1 - np.exp(-t * 300))
        coloured = lfilter([1.0], [1.0, -rng.uniform(0.3, 0.9)], burst)  # a throat's low-pass colour
        end = min(len(out), at + length)
        out[at:end] += coloured[: end - at]
        at = end + _samples(rng.uniform(0.1, 0.6))
    return _level(out + 1e-3 * rng.normal(size=len(out)), dbfs)


def _spoken(
    rng: np.random.Generator, phrases: tuple[str, ...], voices: tuple[str, ...], count: int, dbfs: float
) -> np.ndarray:
    parts = []
    for _ in range(count):
        said = espeak.synthesise(str(rng.choice(phrases)), str(rng.choice(voices)), int(rng.integers(130, 190))).astype(
            np.float64
        )
        parts += [said, np.zeros(_samples(rng.uniform(0.3, 0.8)))]
    return _level(np.concatenate(parts), dbfs)


VOICES = ("en-us", "en-gb", "en-us+f3", "en-us+m3")


def fillers(rng: np.random.Generator, _seconds: float, dbfs: float = -20.0) -> np.ndarray:
    """ "Um", "hmm", "uh huh": the sounds people make while they think."""
    return _spoken(rng, FILLERS, VOICES, 1, dbfs)


def laughter(rng: np.random.Generator, _seconds: float, dbfs: float = -20.0) -> np.ndarray:
    return _spoken(rng, LAUGHTER, VOICES, 1, dbfs)


def babble(rng: np.random.Generator, _seconds: float, dbfs: float = -32.0) -> np.ndarray:
    """A conversation nearby: two off-topic talkers at once, quiet."""
    first = _spoken(rng, OFF_TOPIC, VOICES, 2, dbfs).astype(np.float64)
    second = _spoken(rng, OFF_TOPIC, VOICES, 2, dbfs).astype(np.float64)
    length = max(len(first), len(second))
    mix = np.zeros(length)
    mix[: len(first)] += first
    mix[: len(second)] += second
    return _level(mix, dbfs)


def off_topic(rng: np.random.Generator, _seconds: float, dbfs: float = -20.0) -> np.ndarray:
    """Someone talking, not to the robot, at a normal level."""
    return _spoken(rng, OFF_TOPIC, VOICES, 1, dbfs)


def robot(rng: np.random.Generator, _seconds: float, dbfs: float = -20.0) -> np.ndarray:
    """The robot's own voice (espeak-ng, as the speech service speaks), heard back through the microphone."""
    return _spoken(rng, ROBOT_PHRASES, ("en-us",), 1, dbfs)


Generator = Callable[[np.random.Generator, float], np.ndarray]
KINDS: dict[str, Generator] = {
    "white noise": white,
    "pink noise": pink,
    "brown noise": brown,
    "hum": hum,
    "tones": tone,
    "chords": chords,
    "coughs": coughs,
    "fillers": fillers,
    "laughter": laughter,
    "babble": babble,
    "off-topic speech": off_topic,
    "robot's voice": robot,
}


def sound(kind: str, seed: int, seconds: float = 2.0) -> np.ndarray:
    """One sound of ``kind`` (a key of :data:`KINDS`); spoken kinds last as long as what is said."""
    return KINDS[kind](np.random.default_rng(seed), seconds)


def mixed(speech: np.ndarray, noise: np.ndarray, snr_db: float) -> np.ndarray:
    """``speech`` with ``noise`` (repeated or cut to its length) added at a signal-to-noise ratio of ``snr_db``."""
    voice = np.asarray(speech, dtype=np.float64)
    background = np.resize(np.asarray(noise, dtype=np.float64), len(voice))
    loud = voice[np.abs(voice) > 0.1 * np.abs(voice).max()] if voice.any() else voice
    gain = np.sqrt(np.mean(loud**2) / max(np.mean(background**2), 1e-9)) * 10 ** (-snr_db / 20)
    return np.clip(np.round(voice + gain * background), -32768, 32767).astype(np.int16)
