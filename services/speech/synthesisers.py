"""Synthetic talkers for the speech benchmark: espeak-ng and Flite, any voice, any speed.

Why two synthesisers: voices of one synthesiser share its way of making
speech, so a recogniser tuned on some of them is not tested by the others.
Flite (Festival's small engine, Debian package ``flite``) makes speech
differently from espeak-ng (diphone and cluster unit selection against
formant synthesis), so its voices are kept for the held-out set.
"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from services.speech import espeak
from services.speech.audio import read_wav

FLITE = "flite"
TIMEOUT_S = 30.0


class SynthesiserError(RuntimeError):
    """A synthesiser is missing or failed; the message says how."""


@dataclass(frozen=True)
class Talker:
    """A synthetic voice: ``speed`` is words per minute for espeak-ng, per cent of the normal length for Flite."""

    synthesiser: str  # "espeak-ng" or "flite"
    voice: str
    speed: int

    @property
    def name(self) -> str:
        return f"{self.synthesiser}:{self.voice}@{self.speed}"

    def say(self, text: str) -> np.ndarray:
        """``text`` spoken by this talker, as 16 kHz int16 samples."""
        if self.synthesiser == espeak.ESPEAK:
            return espeak.synthesise(text, self.voice, self.speed)
        if self.synthesiser == FLITE:
            return _flite(text, self.voice, self.speed)
        raise SynthesiserError(f"unknown synthesiser {self.synthesiser!r}")


def available(synthesiser: str) -> bool:
    return shutil.which(synthesiser) is not None


def _flite(text: str, voice: str, stretch_percent: int) -> np.ndarray:
    if not available(FLITE):
        raise SynthesiserError(f"{FLITE} is not installed (Debian package flite)")
    with tempfile.TemporaryDirectory(prefix="hfpbd-flite-") as folder:
        path = Path(folder) / "speech.wav"
        command = [FLITE, "-voice", voice, "--setf", f"duration_stretch={stretch_percent / 100:g}"]
        try:
            result = subprocess.run(
                [*command, "-t", text, "-o", str(path)],
                capture_output=True,
                text=True,
                timeout=TIMEOUT_S,
                stdin=subprocess.DEVNULL,
            )
        except subprocess.TimeoutExpired:
            raise SynthesiserError(f"{FLITE} did not finish within {TIMEOUT_S:g} s") from None
        if result.returncode != 0 or not path.exists():
            detail = (result.stderr.strip().splitlines() or [f"exit code {result.returncode}"])[-1]
            raise SynthesiserError(f"{FLITE} failed: {detail}")
        return read_wav(path)
