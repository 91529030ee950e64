"""PCM helpers: every audio path ends as 16 kHz mono int16, the acoustic model's rate."""

from __future__ import annotations

import math
import wave
from pathlib import Path

import numpy as np
from scipy.signal import resample_poly

RATE = 16000
DITHER_LEVEL = 8.0  # standard deviation in 16-bit steps, about -72 dBFS


class AudioError(ValueError):
    """Audio that cannot be used; the message says why."""


def resample(samples: np.ndarray, rate: int) -> np.ndarray:
    """Resample mono ``samples`` at ``rate`` to :data:`RATE`, as int16."""
    if rate <= 0:
        raise AudioError(f"sample rate must be positive, got {rate}")
    data = np.asarray(samples, dtype=np.float32)
    if rate != RATE:
        common = math.gcd(rate, RATE)
        data = resample_poly(data, RATE // common, rate // common)
    return np.clip(np.round(data), -32768, 32767).astype(np.int16)


def read_wav(path: str | Path) -> np.ndarray:
    """Read a 16-bit PCM WAV file (any rate, mono or stereo) as 16 kHz mono int16."""
    try:
        with wave.open(str(path), "rb") as wav:
            channels, width, rate = wav.getnchannels(), wav.getsampwidth(), wav.getframerate()
            frames = wav.readframes(wav.getnframes())
    except FileNotFoundError:
        raise AudioError(f"no such WAV file: {path}") from None
    except (wave.Error, EOFError) as exc:
        raise AudioError(f"{path} is not a readable WAV file: {exc}") from None
    if width != 2:
        raise AudioError(f"{path}: only 16-bit PCM WAV is supported, this one has {8 * width}-bit samples")
    samples = np.frombuffer(frames, dtype="<i2").astype(np.float32)
    if channels > 1:
        samples = samples[: len(samples) // channels * channels].reshape(-1, channels).mean(axis=1)
    return resample(samples, rate)


def write_wav(path: str | Path, pcm: np.ndarray, rate: int = RATE) -> None:
    with wave.open(str(path), "wb") as wav:
        wav.setnchannels(1)
        wav.setsampwidth(2)
        wav.setframerate(rate)
        wav.writeframes(np.asarray(pcm, dtype="<i2").tobytes())


def dither(pcm: np.ndarray, level: float = DITHER_LEVEL, seed: int = 0) -> np.ndarray:
    """Add faint noise to ``pcm``.

    Why: digitally silent stretches (synthesised speech, WAV files, muted
    inputs) have an energy of minus infinity on the log scale; the
    recogniser's feature normalisation and the voice activity detector then
    misjudge speech next to them. A real microphone always has this much
    noise, so adding it changes nothing for live audio.
    """
    noise = np.random.default_rng(seed).normal(0.0, level, len(pcm))
    return np.clip(np.asarray(pcm, dtype=np.float32) + noise, -32768, 32767).astype(np.int16)


def silence(seconds: float) -> np.ndarray:
    return np.zeros(int(round(seconds * RATE)), dtype=np.int16)


def seconds(pcm: np.ndarray) -> float:
    return len(pcm) / RATE


def same_audio(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two utterances are the very same samples (an early offer and the utterance that ended)."""
    return len(a) == len(b) and bool(np.array_equal(a, b))
