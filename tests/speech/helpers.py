"""Audio sent to the speech service over the bus, as a remote microphone sends it."""

from __future__ import annotations

import numpy as np

from services.speech.audio import RATE
from shared.bus import Bus
from shared.messages import SpeechAudio


def stream(bus: Bus, pcm: np.ndarray, chunk_s: float = 0.1) -> None:
    """Send ``pcm`` (16 kHz int16) on speech/audio in chunks of ``chunk_s``.

    The publisher blocks rather than drops under congestion: a burst of chunks
    sent while the service is busy would otherwise lose some, and a lost
    trailing silence leaves the utterance unfinished.
    """
    publisher = bus.publisher(bus.keys.speech("audio"), large=True)
    step = int(RATE * chunk_s)
    for start in range(0, len(pcm), step):
        publisher.put(SpeechAudio(pcm=pcm[start : start + step], rate=RATE))
