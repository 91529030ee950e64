"""Voice activity detection: a stream of PCM chunks in, whole utterances out."""

from __future__ import annotations

import numpy as np
from pocketsphinx import Endpointer

from services.speech.audio import RATE, dither

MAX_UTTERANCE_S = 15.0  # a command is a few seconds; cut runaway input (a radio left on)


class UtteranceSplitter:
    """Feeds fixed-size frames to PocketSphinx's endpointer and collects each utterance.

    Why buffer: the endpointer only takes frames of exactly ``frame_bytes``,
    while audio arrives in chunks of any size.
    """

    def __init__(self, window_s: float = 0.3, ratio: float = 0.9) -> None:
        self._endpointer = Endpointer(window=window_s, ratio=ratio, sample_rate=RATE)
        self._frame = self._endpointer.frame_bytes // 2
        self._pending = np.zeros(0, dtype=np.int16)
        self._speech: list[bytes] = []
        self._samples = 0

    @property
    def in_speech(self) -> bool:
        return bool(self._endpointer.in_speech)

    def feed(self, pcm: np.ndarray) -> list[np.ndarray]:
        """Add 16 kHz int16 samples; return the utterances that ended within them."""
        data = np.concatenate([self._pending, dither(np.asarray(pcm, dtype=np.int16), seed=self._samples)])
        self._samples += len(pcm)
        done: list[np.ndarray] = []
        whole = len(data) // self._frame * self._frame
        for start in range(0, whole, self._frame):
            speech = self._endpointer.process(data[start : start + self._frame].tobytes())
            if speech is None:
                continue
            self._speech.append(speech)
            if not self._endpointer.in_speech or len(self._speech) * self._frame >= MAX_UTTERANCE_S * RATE:
                done.append(self._take())
        self._pending = data[whole:]
        return done

    def flush(self) -> list[np.ndarray]:
        """End of the stream: the utterance still in progress, if any."""
        if self._endpointer.in_speech:
            # the bindings index the buffer's first sample, so an empty last frame (a stream whose
            # length is a whole number of frames) raises; one silent sample ends the stream the same way
            last = self._pending if len(self._pending) else np.zeros(1, dtype=np.int16)
            tail = self._endpointer.end_stream(last.tobytes())
            if tail is not None:
                self._speech.append(tail)
        self._pending = np.zeros(0, dtype=np.int16)
        return [self._take()] if self._speech else []

    def _take(self) -> np.ndarray:
        utterance = np.frombuffer(b"".join(self._speech), dtype=np.int16).copy()
        self._speech = []
        return utterance
