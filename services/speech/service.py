"""The speech service: audio in, n-best utterances out; the robot's words spoken.

Threads: audio arrives on the microphone's thread or on bus callbacks; it is
split into utterances under a lock, and every decoder operation (decoding,
swapping the grammar) happens on one worker thread, because PocketSphinx is
not thread-safe and decoding must never stall a bus callback.
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import numpy as np

from services.speech.audio import RATE, AudioError, read_wav, resample, same_audio, silence
from services.speech.gate import judge
from services.speech.grammar import SceneWords
from services.speech.microphone import Microphone, MicrophoneUnavailable
from services.speech.recogniser import Hypothesis, Recogniser
from services.speech.vad import UtteranceSplitter
from services.speech.vocabulary import SpeechVocabulary, nlu_vocabulary
from services.speech.voice import Speaker
from shared.bus import Bus, BusTimeout, RemoteError
from shared.messages import (
    ExecutorState,
    Objects,
    PttReply,
    Say,
    SayKind,
    SpeechAudio,
    SpeechPtt,
    SpeechStatus,
    Utterance,
)

log = logging.getLogger("hfpbd.speech")

NOT_HEARD = "I didn't catch that. Please say it again or type it."
WAV_CHUNK_S = 0.1
RELEASE_TAIL_S = 0.4
# a speech/audio stream that sends nothing for this long has stopped (its sender quit or paused
# without saying "end"): what it left half-said is decoded instead of waiting for more audio
STREAM_IDLE_S = 1.0
# how long WAV files given at start wait for the NLU's vocabulary before the built-in grammar decodes them
VOCABULARY_WAIT_S = 30.0


@dataclass
class Settings:
    trigger: str = "vad"  # vad: utterances found by voice activity; ptt: only while talk is pressed
    microphone: str = "auto"  # auto, on (a missing microphone is an error), off
    device: str | None = None
    per_meaning: int | None = 3  # phrases per meaning in the grammar; None: the whole vocabulary
    wav_files: tuple[Path, ...] = ()
    mllr: Path | None = None  # an enrolled voice's MLLR transform (hfpbd speech enrol), else the model as shipped


@dataclass(frozen=True)
class Early:
    """An utterance decoded before its end was sure: what was heard in it (None: no speech), and whether it was sent."""

    pcm: np.ndarray
    hypotheses: list[Hypothesis] | None
    sent: bool


class SpeechService:
    def __init__(self, bus: Bus, settings: Settings, speaker: Speaker | None) -> None:
        self.bus = bus
        self.settings = settings
        self.speaker = speaker
        self.recogniser = Recogniser(nlu_vocabulary(), per_meaning=settings.per_meaning, mllr=settings.mllr)
        self.microphone: Microphone | None = None
        self.microphone_problem: str | None = None
        self._splitter = UtteranceSplitter()
        self._audio_lock = threading.Lock()
        self._talk: list[np.ndarray] | None = None  # audio captured while push-to-talk is held
        self._skills: frozenset[str] = frozenset()  # the skills' names last taken into the grammar
        self._streamed_at: float | None = None  # when the last speech/audio chunk came, while the stream is open
        self._tasks: queue.Queue[Callable[[], None] | None] = queue.Queue()
        self._worker = threading.Thread(target=self._work, name="decoder", daemon=True)
        self._utterances = bus.publisher(bus.keys.utterance)
        self._say = bus.publisher(bus.keys.say)
        self._status = bus.publisher(bus.keys.speech("status"), cached=True)
        self._offered: np.ndarray | None = None  # the splitter's early offer of the utterance in progress
        self._early: Early | None = None  # the last offer decoded ahead
        self.grammar = "built-in"  # or "nlu": whose phrase list the grammar was made from
        # set once the NLU's vocabulary is in the grammar, or known not to be coming (the NLU did not answer)
        self.grammar_settled = threading.Event()

    # -- start and stop ----------------------------------------------------
    def start(self) -> None:
        self._worker.start()
        self.bus.subscribe(self.bus.keys.speech("audio"), self._on_stream, schema="speech_audio")
        self.bus.serve(self.bus.keys.speech("ptt"), self._on_ptt, request=SpeechPtt)
        self.bus.subscribe(self.bus.keys.objects, self._on_objects, schema="objects", latest_only=True, history=True)
        self.bus.subscribe(
            self.bus.keys.executor_state, self._on_executor, schema="executor_state", latest_only=True, history=True
        )
        self.bus.watch_alive(self._on_alive)
        if self.speaker is not None:
            self.bus.subscribe(self.bus.keys.say, self._on_say, schema="say")
        self._open_microphone()
        self._publish_status()

    def close(self) -> None:
        if self.microphone is not None:
            self.microphone.close()
        self._tasks.put(None)
        self._worker.join(timeout=10)
        if self.speaker is not None:
            self.speaker.close()

    def play_files(self) -> None:
        """Decode the WAV files given at start, once the grammar is the running NLU's.

        Why wait: the grammar follows the NLU's vocabulary, fetched when the NLU
        is seen alive; a file decoded before that is heard with the built-in
        phrase list, which may not be the NLU's.
        """
        if not self.settings.wav_files:
            return
        if not self.grammar_settled.wait(VOCABULARY_WAIT_S):
            log.warning(
                "no NLU vocabulary within %g s; decoding the WAV files with the built-in grammar", VOCABULARY_WAIT_S
            )
        for path in self.settings.wav_files:
            try:
                self.feed_file(path)
            except AudioError as exc:
                self._tell(str(exc), "error")

    # -- audio in ------------------------------------------------------------
    def feed(self, pcm: np.ndarray) -> None:
        """16 kHz int16 audio from any source: collected for push-to-talk, else split by voice activity."""
        with self._audio_lock:
            if self._talk is not None:
                self._talk.append(pcm)
                return
            if self.settings.trigger == "ptt":
                return
            utterances = self._splitter.feed(pcm)
            offer = self._offer(self._splitter.candidate)
        if offer is not None:
            self._tasks.put(partial(self._hear_early, offer))
        for utterance in utterances:
            self._tasks.put(partial(self._decode, utterance))

    def _offer(self, candidate: np.ndarray | None) -> np.ndarray | None:
        """The splitter's early offer if it is new (decoded ahead), remembered as the one offered; under the lock."""
        if candidate is not None and self._offered is not None and len(candidate) == len(self._offered):
            return None  # the same offer as before: its frames do not change while no speech comes
        self._offered = candidate
        return candidate

    def end_of_stream(self) -> None:
        with self._audio_lock:
            utterances = self._splitter.flush()
            self._offered = None
        for utterance in utterances:
            self._tasks.put(partial(self._decode, utterance))

    def feed_file(self, path: Path) -> None:
        """A WAV file as if it were spoken now (split into utterances like live audio)."""
        pcm = np.concatenate([read_wav(path), silence(0.5)])
        step = int(RATE * WAV_CHUNK_S)
        for start in range(0, len(pcm), step):
            self.feed(pcm[start : start + step])
        self.end_of_stream()

    def _hears_itself(self) -> bool:
        """Whether the robot is speaking now: what any microphone picks up then is mostly its own voice."""
        return self.speaker is not None and self.speaker.speaking.is_set()

    def _on_microphone(self, pcm: np.ndarray) -> None:
        if not self._hears_itself():
            self.feed(pcm)

    def _on_stream(self, message: SpeechAudio) -> None:
        pcm = np.asarray(message.pcm)
        if pcm.ndim != 1 or pcm.dtype != np.int16:
            log.warning("speech/audio chunk ignored: pcm must be 1-D int16, got %s %s", pcm.dtype, pcm.shape)
            return
        try:
            pcm = resample(pcm, message.rate)
        except AudioError as exc:
            log.warning("speech/audio chunk ignored: %s", exc)
            return
        if not self._hears_itself():  # a remote microphone hears the robot's voice as a local one does
            self.feed(pcm)
        with self._audio_lock:
            self._streamed_at = None if message.end else time.monotonic()
        if message.end:
            self.end_of_stream()

    def _end_idle_stream(self) -> None:
        """Decode what a stream that went quiet mid-utterance left behind."""
        with self._audio_lock:
            idle = self._streamed_at is not None and time.monotonic() - self._streamed_at >= STREAM_IDLE_S
            if idle:
                self._streamed_at = None
        if idle:
            self.end_of_stream()

    # -- push to talk ----------------------------------------------------------
    def _on_ptt(self, press: SpeechPtt) -> PttReply:
        self.set_talk(press.on)
        return PttReply(ok=True, listening=press.on)

    def set_talk(self, on: bool) -> None:
        """Press: collect all audio from now on. Release: decode it, after a short tail.

        Why the tail: people let go of the key while finishing the last word,
        and audio streamed over the bus may still be in flight.
        """
        if on:
            with self._audio_lock:
                if self._talk is None:
                    self._talk = []
                    self._splitter = UtteranceSplitter()  # what was half-heard before the press is dropped
                    self._offered = None
        else:
            release = threading.Timer(RELEASE_TAIL_S, self._release)
            release.daemon = True
            release.start()
        self._publish_status()

    def _release(self) -> None:
        with self._audio_lock:
            talk, self._talk = self._talk, None
        if talk:
            pcm = np.concatenate(talk)
            self._tasks.put(lambda: self._decode(pcm))
        self._publish_status()

    # -- decoding --------------------------------------------------------------
    def _work(self) -> None:
        """Run decoder tasks in order; when none is waiting, notice streams that stopped.

        Why only when idle: right after a long task the bus handler may not yet
        have taken the chunks that queued meanwhile, so the stream would look
        stopped when it is not.
        """
        while True:
            try:
                task = self._tasks.get(timeout=STREAM_IDLE_S / 4)
            except queue.Empty:
                self._end_idle_stream()
                continue
            if task is None:
                return
            try:
                task()
            except Exception:
                log.exception("speech task failed")

    def _hear_early(self, pcm: np.ndarray) -> None:
        """Decode an utterance the splitter offered before its end was sure, unless the offer was withdrawn since.

        A stop heard in it (by hypotheses holding the share the NLU acts on a
        stop at) goes out at once, without waiting for the end to be sure:
        stopping when more words follow costs a repeat of them, while waiting
        0.27 s more lets the arm move on. When the utterance then ends as
        offered, it is not sent again.
        """
        with self._audio_lock:
            current = self._offered is pcm
        if not current:
            return
        hypotheses = self._hear(pcm)
        sent = False
        if hypotheses and self.recogniser.heard_stop(hypotheses):
            log.info("a stop heard before the end of the utterance was sure: sent at once")
            self._utterances.put(utterance_message(hypotheses))
            sent = True
        self._early = Early(pcm, hypotheses, sent)

    def _decode(self, pcm: np.ndarray) -> None:
        """An utterance that ended: what was heard in it is said, from the early decoding when that had this audio."""
        early, self._early = self._early, None
        if early is not None and same_audio(early.pcm, pcm):
            if early.sent:
                return
            hypotheses = early.hypotheses
        else:
            hypotheses = self._hear(pcm)
        if hypotheses is None:
            return
        if not hypotheses:
            self._tell(NOT_HEARD, "info")
            return
        self._utterances.put(utterance_message(hypotheses))

    def _hear(self, pcm: np.ndarray) -> list[Hypothesis] | None:
        """The n-best heard in one utterance, or None when it is no speech at all, which is dropped without a word.

        Why silently: a cough or a door is not addressed to the robot, and a
        reply to each would be noise of its own.
        """
        started = time.monotonic()
        verdict = judge(pcm)
        if not verdict.speech:
            log.info("%.1f s of sound ignored: %s", len(pcm) / RATE, verdict.reason)
            return None
        hypotheses = self.recogniser.decode(pcm)
        log.info(
            "decoded %.1f s of audio in %.2f s: %s",
            len(pcm) / RATE,
            time.monotonic() - started,
            " | ".join(f"{h.text} ({h.score:.2f})" for h in hypotheses) or "nothing",
        )
        return hypotheses

    # -- vocabulary and scene ---------------------------------------------------
    def _on_alive(self, service: str, alive: bool) -> None:
        if service == "nlu" and alive:
            threading.Thread(target=self._fetch_vocabulary, name="vocabulary", daemon=True).start()

    def _fetch_vocabulary(self) -> None:
        """The running NLU's own phrase list: the grammar follows it when the NLU changes."""
        try:
            reply = self.bus.request(self.bus.keys.nlu_query("vocabulary"), {}, timeout=10.0)
        except (BusTimeout, RemoteError) as exc:
            log.warning("could not read the NLU's vocabulary (%s); keeping the built-in one", exc)
            self.grammar_settled.set()
            return
        phrases = reply.get("phrases")
        if not isinstance(phrases, list) or not phrases:
            log.warning("the NLU's vocabulary reply has no phrases; keeping the built-in one")
            self.grammar_settled.set()
            return
        vocabulary = nlu_vocabulary([str(p) for p in phrases])
        self._tasks.put(lambda: self._regenerate(vocabulary))

    def _regenerate(self, vocabulary: SpeechVocabulary) -> None:
        self.recogniser.set_vocabulary(vocabulary)
        self.grammar = "nlu"
        log.info("speech grammar regenerated from the NLU's vocabulary (%d words)", len(vocabulary.words()))
        self._publish_status()
        self.grammar_settled.set()

    def _on_objects(self, message: Objects) -> None:
        """The grammar's object words come from the NLU's world-state reading, so the objects go in as that JSON."""
        scene = SceneWords.of([o.world_state() for o in message.objects])
        self._tasks.put(lambda: self.recogniser.set_scene(scene))

    def _on_executor(self, message: ExecutorState) -> None:
        """The taught skills' names become verbs of the grammar ("serve the blue cup")."""
        names = frozenset(skill.name for skill in message.skills)
        if names != self._skills:
            self._skills = names
            self._tasks.put(lambda: self._take_skills(names))

    def _take_skills(self, names: frozenset[str]) -> None:
        self.recogniser.set_skills(names)
        self._publish_status()  # says which names can now be said

    # -- output -------------------------------------------------------------------
    def _on_say(self, message: Say) -> None:
        assert self.speaker is not None
        was_working = self.speaker.working
        self.speaker.say(message.text)
        if was_working and not self.speaker.working:
            self._publish_status()

    def _open_microphone(self) -> None:
        if self.settings.microphone == "off":
            return
        try:
            self.microphone = Microphone(self._on_microphone, self.settings.device)
            log.info("listening on the microphone (%s)", self.settings.trigger)
        except MicrophoneUnavailable as exc:
            if self.settings.microphone == "on":
                raise
            self.microphone_problem = str(exc)
            self._tell(
                f"No microphone: {exc}. Speech works from WAV files and the speech/audio stream; "
                "typing works as always.",
                "info",
            )

    def _tell(self, text: str, kind: SayKind) -> None:
        """Something the user must know: logged here and shown (and spoken) like the robot's words."""
        (log.warning if kind == "error" else log.info)("%s", text)
        self._say.put(Say(text=text, kind=kind))

    def _publish_status(self) -> None:
        self._status.put(
            SpeechStatus(
                stamp=time.time(),
                microphone=self.microphone is not None,
                microphone_problem=self.microphone_problem,
                voice=self.speaker is not None and self.speaker.working,
                voice_problem=self.speaker.problem if self.speaker is not None else None,
                trigger=self.settings.trigger,
                talking=self._talk is not None,
                grammar_words=len(self.recogniser.vocabulary.words()),
                grammar=self.grammar,
                skills=sorted(self.recogniser.skills),
            )
        )


def utterance_message(hypotheses: list[Hypothesis]) -> Utterance:
    """``dialog/utterance`` for the NLU: the top string plus the n-best to rescore."""
    return Utterance(text=hypotheses[0].text, source="speech", nbest=[h.to_json() for h in hypotheses])
