"""Voice activity detection: a stream of PCM chunks in, whole utterances out, each offered early as it may end.

Frames of 30 ms are classed speech or not by PocketSphinx's voice activity
detector. An utterance starts when nine of the last ten frames are speech
(the last nine of those ten are its first), and ends when ten frames in a
row are not, with the one after its last speech frame as its tail: an end
is known 0.3 s after the last word, because a shorter pause is a person
drawing breath within a sentence. These are the cuts PocketSphinx's own
endpointer makes (the very same audio in 100 of 102 utterances of the
speech benchmark compared), so the gate, the decoder and the figures
measured on them see what they saw.

Why not that endpointer, and why the early offer (``candidate``): the
endpointer hands out an utterance only when its end is sure, while the
utterance is whole one frame after the last word. It is offered then, so
that the decoder can start on it while the end is still being confirmed:
when the end comes with no speech between, the utterance is exactly the one
offered and its decoding is done or under way; when speech resumes, the
offer is withdrawn and the sentence goes on.
"""

from __future__ import annotations

from collections import deque

import numpy as np
from pocketsphinx import Vad

from services.speech.audio import RATE, dither

MAX_UTTERANCE_S = 15.0  # a command is a few seconds; cut runaway input (a radio left on)
WINDOW_FRAMES = 10  # 0.3 s: the frames a start or an end is judged on
START_SPEECH_FRAMES = 9  # of the window's frames, how many must be speech to start an utterance
LEAD_FRAMES = 9  # frames of the starting window that open an utterance (its last nine, as PocketSphinx's endpointer)
TAIL_FRAMES = 1  # non-speech frames after the last speech frame that end an utterance's audio (as the endpointer)


class UtteranceSplitter:
    """Feeds fixed-size frames to PocketSphinx's voice activity detector and collects each utterance.

    Why buffer: the detector only takes frames of exactly ``frame_bytes``,
    while audio arrives in chunks of any size.
    """

    def __init__(self) -> None:
        self._vad = Vad(Vad.LOOSE, RATE)
        self._frame = self._vad.frame_bytes // 2
        self._pending = np.zeros(0, dtype=np.int16)
        self._recent: deque[tuple[bool, np.ndarray]] = deque(maxlen=WINDOW_FRAMES)  # before an utterance starts
        self._frames: list[np.ndarray] = []  # the utterance in progress, up to its last speech frame and any after
        self._last_speech = 0  # frames of the utterance up to and including its last speech frame
        self._samples = 0

    @property
    def in_speech(self) -> bool:
        return bool(self._frames)

    @property
    def candidate(self) -> np.ndarray | None:
        """The utterance in progress as it will end if no speech follows; None while it may still go on."""
        if not self._frames or len(self._frames) - self._last_speech < TAIL_FRAMES:
            return None
        return np.concatenate(self._frames[: self._last_speech + TAIL_FRAMES])

    def feed(self, pcm: np.ndarray) -> list[np.ndarray]:
        """Add 16 kHz int16 samples; return the utterances that ended within them."""
        data = np.concatenate([self._pending, dither(np.asarray(pcm, dtype=np.int16), seed=self._samples)])
        self._samples += len(pcm)
        done: list[np.ndarray] = []
        whole = len(data) // self._frame * self._frame
        for start in range(0, whole, self._frame):
            frame = data[start : start + self._frame]
            ended = self._step(bool(self._vad.is_speech(frame.tobytes())), frame)
            if ended is not None:
                done.append(ended)
        self._pending = data[whole:]
        return done

    def flush(self) -> list[np.ndarray]:
        """End of the stream: the utterance still in progress, if any, with all of it heard so far."""
        utterance = self._frames + ([self._pending] if self._frames and len(self._pending) else [])
        self._pending = np.zeros(0, dtype=np.int16)
        self._frames, self._last_speech = [], 0
        self._recent.clear()
        return [np.concatenate(utterance)] if utterance else []

    def _step(self, speech: bool, frame: np.ndarray) -> np.ndarray | None:
        """One frame on: an utterance starts, goes on or ends (returned)."""
        if not self._frames:
            self._recent.append((speech, frame))
            labels = [is_speech for is_speech, _ in self._recent]
            if sum(labels) >= START_SPEECH_FRAMES:
                self._frames = [f for _, f in self._recent][-LEAD_FRAMES:]
                self._last_speech = LEAD_FRAMES - labels[::-1].index(True)
                self._recent.clear()
            return None
        self._frames.append(frame)
        if speech:
            self._last_speech = len(self._frames)
        if len(self._frames) * self._frame >= MAX_UTTERANCE_S * RATE:
            return self._take(len(self._frames))
        if len(self._frames) - self._last_speech >= WINDOW_FRAMES:
            return self._take(self._last_speech + TAIL_FRAMES)
        return None

    def _take(self, frames: int) -> np.ndarray:
        utterance = np.concatenate(self._frames[:frames])
        self._frames, self._last_speech = [], 0
        return utterance
