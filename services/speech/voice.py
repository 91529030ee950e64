"""The robot's voice: what it says on ``dialog/say``, spoken one sentence at a time."""

from __future__ import annotations

import logging
import queue
import threading
from pathlib import Path

from services.speech import espeak

log = logging.getLogger("hfpbd.speech")


class Speaker:
    """Speaks queued sentences with espeak-ng, to the loudspeaker or as WAV files in ``folder``.

    Why a queue and one thread: sentences must not overlap, and the bus
    callback that receives them must not wait for the audio to finish.
    A missing audio output is reported once; after that the speaker falls
    silent instead of failing on every sentence.
    """

    def __init__(self, voice: str = "en-us", speed: int = 160, folder: Path | None = None) -> None:
        self.voice, self.speed, self.folder = voice, speed, folder
        self.speaking = threading.Event()
        self.problem: str | None = None
        self.spoken = 0
        self._queue: queue.Queue[str | None] = queue.Queue()
        self._thread = threading.Thread(target=self._run, name="speaker", daemon=True)
        self._thread.start()

    @property
    def working(self) -> bool:
        return self.problem is None

    def say(self, text: str) -> None:
        if text.strip() and self.working:
            self._queue.put(text.strip())

    def close(self) -> None:
        self._queue.put(None)
        self._thread.join(timeout=espeak.TIMEOUT_S)

    def _run(self) -> None:
        while (text := self._queue.get()) is not None:
            if not self.working:
                continue
            self.speaking.set()
            try:
                if self.folder is not None:
                    self.spoken += 1
                    espeak.write(text, self.folder / f"say-{self.spoken:04d}.wav", self.voice, self.speed)
                else:
                    espeak.play(text, self.voice, self.speed)
                    self.spoken += 1
            except espeak.EspeakError as exc:
                self.problem = (
                    f"cannot speak: {exc} (is there an audio output?); spoken feedback is off, the text still shows"
                )
                log.warning("%s", self.problem)
            finally:
                self.speaking.clear()
