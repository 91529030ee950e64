"""Live microphone capture, optional: without PortAudio or an input device, say why once.

Why optional: speech is one way in among several (typing, WAV files, a
remote audio stream). A machine without audio hardware must still run the
service, and the user must learn once, plainly, that the microphone is not
in use, rather than meet a traceback or silence.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from services.speech.audio import RATE

BLOCK_S = 0.1


class MicrophoneUnavailable(RuntimeError):
    """No usable microphone; the message says what is missing."""


class Microphone:
    """A 16 kHz mono capture stream that hands each block of samples to ``on_audio``."""

    def __init__(self, on_audio: Callable[[np.ndarray], None], device: str | int | None = None) -> None:
        try:
            import sounddevice
        except (ImportError, OSError) as exc:
            raise MicrophoneUnavailable(
                f"audio capture is not available ({exc}; Debian package libportaudio2)"
            ) from None
        self._on_audio = on_audio
        try:
            self._stream: Any = sounddevice.InputStream(
                samplerate=RATE,
                channels=1,
                dtype="int16",
                blocksize=int(RATE * BLOCK_S),
                device=device,
                callback=self._callback,
            )
            self._stream.start()
        except Exception as exc:  # PortAudioError, ValueError: no (such) input device
            raise MicrophoneUnavailable(f"no microphone could be opened ({exc})") from None

    def _callback(self, block: np.ndarray, _frames: int, _time: Any, _status: Any) -> None:
        self._on_audio(block[:, 0].copy())

    def close(self) -> None:
        self._stream.stop()
        self._stream.close()
