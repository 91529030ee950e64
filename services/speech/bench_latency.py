"""``hfpbd bench speech-latency``: from the end of a spoken command to the NLU's result, through the running services.

What a person waits for after the last word: the voice activity detector
noticing the silence, the gate, both recogniser passes, the NLU's choice
among the n-best and its ``nlu/result``. The speech and NLU services run as
processes; the benchmark plays a remote microphone, streaming audio on
``speech/audio`` in 100 ms chunks at the pace it would be spoken, and
publishes a table of objects as perception would.

Each trial is one command from a held-out talker (never tuned on), between
silences. The end of speech is the last sample within 30 dB of the loudest
one; the time it was "said" is when the chunk holding it was due, less what
followed it in that chunk. Two delays are measured from there: to the
``dialog/utterance`` the speech service publishes (endpointing, gate and
decoding) and to the ``nlu/result`` (the NLU too). A second condition puts
seconds of noise (babble, a cough, hum, off-topic talk) right before each
command: the noise must not hold up the command after it.
"""

from __future__ import annotations

import argparse
import queue
import tempfile
import time
import uuid
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hfpbd.tasks.stack import LocalStack
from services.nlu.nbest import NOT_MADE_OUT
from services.speech import sounds
from services.speech.audio import RATE, silence
from services.speech.corpus import HELD_OUT_SPEEDS, HELD_OUT_VOICES
from services.speech.espeak import ESPEAK
from services.speech.synthesisers import FLITE, Talker, available
from shared.bus import Bus
from shared.config import free_port, loopback_options
from shared.messages import Objects, PerceivedObject, Say, SpeechAudio, SpeechStatus

CHUNK_S = 0.1
LEAD_S = 0.5  # silence before each command
TAIL_S = 1.5  # silence after it: longer than the endpointer needs
END_DB = 30.0  # the end of speech: the last sample within this many decibels of the loudest
TARGET_P95_S = 0.5
RESULT_TIMEOUT_S = 15.0
NOISES = ("babble", "coughs", "hum", "off-topic speech")
NOISE_S = 3.0
SENTENCES = (
    "pick up the red cup",
    "move your right hand above the blue cup",
    "put it on the green box",
    "open your left hand",
    "point at the green box with your left hand",
    "look at the blue cup",
    "move your left arm up five centimetres",
    "stop",
    "execute",
    "what are you holding",
)
OBJECTS = [
    PerceivedObject(id="obj0", color="red", type="cup", position=(0.55, -0.15, 0.77), size=(0.07, 0.07, 0.1)),
    PerceivedObject(id="obj1", color="blue", type="cup", position=(0.6, 0.15, 0.77), size=(0.07, 0.07, 0.1)),
    PerceivedObject(id="obj2", color="green", type="box", position=(0.5, 0.0, 0.76), size=(0.08, 0.08, 0.08)),
]


@dataclass(frozen=True)
class Trial:
    """One streamed command: its delays from the end of speech (None: nothing came)."""

    condition: str
    text: str
    talker: str
    to_utterance_s: float | None
    to_result_s: float | None


def talkers() -> list[Talker]:
    """Held-out talkers: Flite's voices when installed, else espeak-ng's held-out voices."""
    if available(FLITE):
        return [Talker(FLITE, voice, 100) for voice in ("kal", "awb", "rms", "slt")]
    return [Talker(ESPEAK, voice, speed) for voice, speed in zip(HELD_OUT_VOICES, HELD_OUT_SPEEDS, strict=False)]


def speech_end(pcm: np.ndarray) -> int:
    """Index just after the last sample within :data:`END_DB` of the loudest one."""
    level = np.abs(pcm.astype(np.float64))
    loud = np.flatnonzero(level >= level.max() * 10 ** (-END_DB / 20))
    return int(loud[-1]) + 1 if len(loud) else len(pcm)


class Listener:
    """The utterances and results as they arrive, stamped on this process's monotonic clock."""

    def __init__(self, bus: Bus) -> None:
        self.utterances: queue.Queue[float] = queue.Queue()
        self.answers: queue.Queue[float] = queue.Queue()  # an nlu/result, or "I didn't catch that"
        self.status: queue.Queue[SpeechStatus] = queue.Queue()
        bus.subscribe(bus.keys.utterance, lambda _: self.utterances.put(time.monotonic()), schema="utterance")
        bus.subscribe(bus.keys.nlu_result, lambda _: self.answers.put(time.monotonic()), schema="nlu_result")
        bus.subscribe(bus.keys.say, self._on_say, schema="say")
        bus.subscribe(bus.keys.speech("status"), self.status.put, schema="speech_status", history=True)

    def _on_say(self, message: Say) -> None:
        if message.text == NOT_MADE_OUT:
            self.answers.put(time.monotonic())

    def drain(self) -> None:
        for inbox in (self.utterances, self.answers):
            while not inbox.empty():
                inbox.get_nowait()

    def grammar_loaded(self, timeout: float) -> bool:
        """Wait until the speech service says its grammar is the running NLU's."""
        deadline = time.monotonic() + timeout
        while (left := deadline - time.monotonic()) > 0:
            try:
                if self.status.get(timeout=left).grammar == "nlu":
                    return True
            except queue.Empty:
                return False
        return False


def stream_live(bus: Bus, pcm: np.ndarray) -> float:
    """Send ``pcm`` on speech/audio at the pace it would be spoken; when the first sample was due (monotonic)."""
    publisher = bus.publisher(bus.keys.speech("audio"), large=True)
    step = int(RATE * CHUNK_S)
    start = time.monotonic()
    for index, first in enumerate(range(0, len(pcm), step)):
        due = start + (index + 1) * CHUNK_S  # a chunk exists once its last sample was spoken
        time.sleep(max(0.0, due - time.monotonic()))
        publisher.put(SpeechAudio(pcm=pcm[first : first + step], rate=RATE))
    return start


def trial(bus: Bus, listener: Listener, condition: str, text: str, talker: Talker, before: np.ndarray) -> Trial:
    said = talker.say(text)
    spoken = said[: speech_end(said)]
    pcm = np.concatenate([before, silence(LEAD_S), spoken, silence(TAIL_S)])
    listener.drain()
    start = stream_live(bus, pcm)
    ended = start + (len(before) + int(LEAD_S * RATE) + len(spoken)) / RATE
    to_utterance = to_result = None
    deadline = time.monotonic() + RESULT_TIMEOUT_S
    try:
        while to_utterance is None:  # an utterance heard in the noise before the command is not the command's
            at = listener.utterances.get(timeout=max(0.0, deadline - time.monotonic()))
            to_utterance = at - ended if at >= ended else None
        while to_result is None:  # after the end of speech: the two keys' callbacks may run in either order
            at = listener.answers.get(timeout=max(0.0, deadline - time.monotonic()))
            to_result = at - ended if at >= ended else None
    except queue.Empty:
        pass
    return Trial(condition, text, talker.name, to_utterance, to_result)


def report(trials: list[Trial]) -> bool:
    """Per condition: how many came through, and the delays' p50, p95 and max; True when every p95 is on target."""
    print(
        f"{'condition':<22} {'trials':>6} {'results':>7}  {'to utterance p50/p95':>22}  {'to result p50/p95/max':>24}"
    )
    met = True
    for condition in dict.fromkeys(t.condition for t in trials):
        group = [t for t in trials if t.condition == condition]
        heard = [t.to_utterance_s for t in group if t.to_utterance_s is not None]
        done = [t.to_result_s for t in group if t.to_result_s is not None]
        if not done:
            print(f"{condition:<22} {len(group):>6} {0:>7}")
            met = False
            continue
        p95 = float(np.percentile(done, 95))
        met &= p95 <= TARGET_P95_S
        print(
            f"{condition:<22} {len(group):>6} {len(done):>7}  "
            f"{np.percentile(heard, 50):>9.3f} / {np.percentile(heard, 95):.3f} s  "
            f"{np.percentile(done, 50):>8.3f} / {p95:.3f} / {max(done):.3f} s"
        )
    print(f"target: end of speech to nlu/result p95 <= {TARGET_P95_S:.1f} s: {'PASS' if met else 'MISS'}")
    return met


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="hfpbd bench speech-latency", description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=1, help="times each sentence is said per condition")
    parser.add_argument("--logs", type=Path, default=None, help="where the services' logs go (default: a temp dir)")
    args = parser.parse_args(argv)
    namespace, port = "hear" + uuid.uuid4().hex[:8], free_port()
    trials: list[Trial] = []
    voices = talkers()
    with Bus(loopback_options(namespace, port, listen=True)) as bus, tempfile.TemporaryDirectory() as data:
        session = loopback_options(namespace, port, listen=False).to_argv()
        stack = LocalStack(bus, args.logs or Path(data) / "logs")
        listener = Listener(bus)
        bus.publisher(bus.keys.objects, cached=True).put(Objects(stamp=time.time(), objects=OBJECTS))
        try:
            stack.start("nlu", session)
            stack.start("speech", session, "--microphone", "off", "--no-voice")
            if not listener.grammar_loaded(60.0):
                print("the speech service never loaded the NLU's grammar")
                return 1
            for round_ in range(args.rounds):
                for index, text in enumerate(SENTENCES):
                    talker = voices[(index + round_) % len(voices)]
                    trials.append(trial(bus, listener, "quiet before", text, talker, np.zeros(0, np.int16)))
                    noise = NOISES[(index + round_) % len(NOISES)]
                    before = sounds.sound(noise, seed=20_000 + 100 * round_ + index, seconds=NOISE_S)
                    trials.append(trial(bus, listener, "noise just before", text, talker, before))
                    print(
                        f"{trials[-2].talker}: {text!r}: {trials[-2].to_result_s}, after {noise}: "
                        f"{trials[-1].to_result_s}",
                        flush=True,
                    )
        finally:
            stack.stop()
    return 0 if report(trials) else 1
