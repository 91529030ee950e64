"""Is it speech at all? A cheap test run on every utterance before the recogniser sees it.

Why before decoding: a command grammar forces every sound onto some
sentence, so hiss becomes "close" and a cough "undo"; and the search over a
sound that fits no sentence well is the slowest of all (seconds of CPU per
second of hiss). Two properties of the short-time spectrum tell most
non-speech apart for a few milliseconds of arithmetic:

- Modulation: speech changes its spectrum several times a second (syllables,
  formant movements); hum, tones, chords, fans and hiss stay the same from
  one twentieth of a second to the next. The measure is the median, over
  the loud frames, of how much the smoothed log band energies change in
  50 ms. Loud means well above the background (the quietest frames), so
  that a steady noise under speech does not count as the sound itself.
- Flatness: every speech sound has a shaped spectrum (formants, harmonics)
  in some of its frames; a cough, a hiss or a breath is noise-like
  throughout. The measure is a low percentile of the spectral flatness over
  the loud frames: speech has frames far from flat, noise bursts have none.

What passes (filler sounds, laughter, conversation, the robot's own voice)
is speech-like, and it is the recogniser's and the NLU's agreement that
keeps it from becoming a command (``services.nlu.nbest``).

Thresholds were chosen on the tuning sounds of the speech benchmark, with a
wide margin on both sides.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from services.speech.audio import RATE

WINDOW = 400  # samples: 25 ms
HOP = 160  # samples: 10 ms
LOUD_DB = 25.0  # frames within this many decibels of the loudest one are the sound; the rest is background
ABOVE_FLOOR_DB = 6.0  # ... and this far above the background's level (the quietest tenth of the frames)
SMOOTH = 5  # frames of smoothing and of the lag over which the spectrum's change is measured (50 ms)
MIN_MODULATION = 0.7  # clean speech 1.2 and more, in noise at 20 dB 0.9 and more; steady sounds 0.55 and less
MAX_FLATNESS = 0.15  # speech 0.02 and less, noise bursts 0.3 and more
FLATNESS_PERCENTILE = 20
MIN_SPEECH_S = 0.15  # shorter than the shortest word


@dataclass(frozen=True)
class Verdict:
    """Whether an utterance sounds like speech, and the measures that said so (for logs and the benchmark)."""

    speech: bool
    modulation: float
    flatness: float
    reason: str = ""


def judge(pcm: np.ndarray) -> Verdict:
    """Judge 16 kHz int16 audio; a non-speech verdict says why."""
    data = np.asarray(pcm, dtype=np.float64)
    if len(data) < max(WINDOW + (SMOOTH + 1) * HOP, int(MIN_SPEECH_S * RATE)):
        return Verdict(False, 0.0, 1.0, "too short for a word")
    count = 1 + (len(data) - WINDOW) // HOP
    frames = data[np.arange(WINDOW)[None, :] + HOP * np.arange(count)[:, None]] * np.hanning(WINDOW)
    power = np.abs(np.fft.rfft(frames, n=512, axis=1)) ** 2 + 1e-3
    energy = 10 * np.log10(power.sum(axis=1))
    loud = (energy > energy.max() - LOUD_DB) & (energy > np.percentile(energy, 10) + ABOVE_FLOOR_DB)
    if loud.sum() < SMOOTH + 1:
        return Verdict(False, 0.0, 1.0, "nothing louder than the background")
    # 16 bands spaced logarithmically from 125 Hz to 8 kHz, roughly as hearing resolves them
    edges = np.unique(np.round(np.geomspace(4, 256, 17)).astype(int))
    bands = np.log(np.add.reduceat(power[:, :256], edges[:-1], axis=1))
    kernel = np.ones(SMOOTH) / SMOOTH
    smooth = np.apply_along_axis(np.convolve, 0, bands, kernel, mode="same")
    change = np.sqrt(np.mean((smooth[SMOOTH:] - smooth[:-SMOOTH]) ** 2, axis=1))
    both_loud = loud[SMOOTH:] & loud[:-SMOOTH]
    modulation = float(np.median(change[both_loud])) if both_loud.any() else 0.0
    voice_band = power[:, 4:200]  # 125 Hz to 6 kHz
    flat = np.exp(np.mean(np.log(voice_band), axis=1)) / np.mean(voice_band, axis=1)
    flatness = float(np.percentile(flat[loud], FLATNESS_PERCENTILE))
    if flatness > MAX_FLATNESS:
        return Verdict(False, modulation, flatness, "noise-like throughout (a cough, a breath, hiss)")
    if modulation < MIN_MODULATION:
        return Verdict(False, modulation, flatness, "steady (hum, a tone, music, a fan)")
    return Verdict(True, modulation, flatness)
