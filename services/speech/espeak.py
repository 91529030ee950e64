"""espeak-ng: speech synthesis, both to the loudspeaker and into WAV data.

Why a subprocess: espeak-ng is a Debian program, not a Python library; one
short-lived process per sentence keeps a hung synthesiser from taking the
service down with it.
"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from services.speech.audio import read_wav

ESPEAK = "espeak-ng"
TIMEOUT_S = 30.0


class EspeakError(RuntimeError):
    """espeak-ng is missing or failed; the message says how."""


def available() -> bool:
    return shutil.which(ESPEAK) is not None


def _command(text: str, voice: str, speed: int, extra: list[str]) -> list[str]:
    if not available():
        raise EspeakError(f"{ESPEAK} is not installed (Debian package espeak-ng)")
    return [ESPEAK, "-v", voice, "-s", str(speed), *extra, "--", text]


def synthesise(text: str, voice: str = "en-us", speed: int = 160) -> np.ndarray:
    """``text`` spoken by espeak-ng, as 16 kHz int16 samples."""
    with tempfile.TemporaryDirectory(prefix="hfpbd-espeak-") as folder:
        path = Path(folder) / "speech.wav"
        write(text, path, voice, speed)
        return read_wav(path)


def write(text: str, path: str | Path, voice: str = "en-us", speed: int = 160) -> None:
    """Write ``text`` spoken by espeak-ng to a WAV file."""
    _run(_command(text, voice, speed, ["-w", str(path)]))


def play(text: str, voice: str = "en-us", speed: int = 160) -> None:
    """Speak ``text`` on the default audio output; raises when there is none."""
    _run(_command(text, voice, speed, []))


def phonemes(word: str, voice: str = "en-us") -> str:
    """espeak-ng's phoneme mnemonics for ``word``, separated by ``_`` (its letter-to-sound rules, nothing spoken)."""
    return _run(_command(word, voice, 160, ["-q", "-x", "--sep=_"]))


def _run(command: list[str]) -> str:
    try:
        result = subprocess.run(command, capture_output=True, text=True, timeout=TIMEOUT_S, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        raise EspeakError(f"{ESPEAK} did not finish within {TIMEOUT_S:g} s") from None
    # espeak-ng exits 0 even when it cannot open the audio device; its error is on stderr
    errors = [
        line for line in result.stderr.splitlines() if "error" in line.lower() and not line.startswith("ALSA lib")
    ]
    if result.returncode != 0 or errors:
        detail = (errors or result.stderr.strip().splitlines() or [f"exit code {result.returncode}"])[-1]
        raise EspeakError(f"{ESPEAK} failed: {detail}")
    return result.stdout
