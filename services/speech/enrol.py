"""``hfpbd speech enrol``: a person reads the prompted sentences and the recogniser adapts to their voice.

The flow: each sentence of :data:`services.speech.prompts.PROMPTS` is read
aloud (recorded from the microphone, or taken from ``prompt_NN.wav`` files),
each recording is checked before it is used, and SphinxTrain estimates one
MLLR transform of the acoustic model from them (:mod:`services.speech.adapt`).
The transform is the voice's profile, ``<voices dir>/<name>/mllr_matrix``;
``hfpbd speech --speaker NAME`` decodes with it.

Why each recording is checked: a recording of the wrong line, of silence or
of half a sentence would teach the transform the wrong sounds, and the
person can only fix it while they are still at the microphone. A recording
must be long enough, sound like speech (the gate that guards the recogniser,
:mod:`services.speech.gate`), and must not be heard as another prompt when
a decoder chooses among the prompts alone (the wrong line read). A reading
that decoder cannot place at all is still used: the voices that most need
adapting are the ones the shipped model hears worst, so only SphinxTrain's
alignment of the audio to its own sentence decides, and a reading that does
not fit (half a sentence, other words) is left out by it and named.
"""

from __future__ import annotations

import argparse
import queue
import re
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pocketsphinx import Decoder

from services.executor.store import default_data_dir
from services.speech.adapt import Adaptation, AdaptationError, Reading, solve_mllr
from services.speech.audio import RATE, AudioError, dither, read_wav, seconds, silence, write_wav
from services.speech.gate import judge
from services.speech.microphone import Microphone, MicrophoneUnavailable
from services.speech.prompts import PROMPTS, prompt_file
from services.speech.vad import UtteranceSplitter

DEFAULT_NAME = "default"
MATRIX_FILE = "mllr_matrix"
RECORDINGS = "recordings"  # the profile keeps what was read, so the voice can be enrolled again from it
NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}")
MIN_RECORDING_S = 0.6  # shorter than any prompt read at any speed
MIN_USABLE = 12  # recordings that passed their checks, of the twenty
PAD_S = 0.3  # silence around each recording: bw aligns the sentence between silences
ATTEMPTS = 3  # tries per prompt at the microphone
LISTEN_S = 15.0  # how long to wait for a prompt to be read
PAUSE_END_S = 1.2  # silence after speech that ends a reading (a shorter pause may be mid-sentence)


class EnrolmentError(RuntimeError):
    """Enrolment cannot go on; the message says why and what to do."""


def voices_dir() -> Path:
    """Where voice profiles live: ``voices`` in the project's data directory (``~/.local/share/hfpbd``)."""
    return default_data_dir() / "voices"


def profile_dir(name: str, root: Path | None = None) -> Path:
    if not NAME.fullmatch(name):
        raise EnrolmentError(
            f"{name!r} cannot name a voice: use letters, digits, '.', '_' or '-' (up to 64, starting with a letter or digit)"
        )
    return (root or voices_dir()) / name


def matrix_path(name: str, root: Path | None = None) -> Path:
    """The enrolled voice's MLLR transform; raises when ``name`` was never enrolled."""
    path = profile_dir(name, root) / MATRIX_FILE
    if not path.is_file():
        raise EnrolmentError(
            f"no enrolled voice {name!r} (no {path}); enrol it with 'hfpbd speech enrol --name {name}'"
        )
    return path


class PromptListener:
    """Which prompt a recording sounds like, to a decoder that knows only the prompts."""

    def __init__(self, prompts: Sequence[str]) -> None:
        self._decoder = Decoder(lm=None, loglevel="FATAL")
        alternatives = " | ".join(f"( {p} )" for p in prompts)
        self._decoder.add_jsgf_string("prompts", f"#JSGF V1.0;\ngrammar prompts;\npublic <prompt> = {alternatives};\n")
        self._decoder.activate_search("prompts")

    def heard(self, pcm: np.ndarray) -> str | None:
        self._decoder.start_utt()
        self._decoder.process_raw(dither(pcm).tobytes(), no_search=False, full_utt=True)
        self._decoder.end_utt()
        hyp = self._decoder.hyp()
        return hyp.hypstr if hyp is not None and hyp.hypstr else None


@dataclass(frozen=True)
class Recording:
    number: int  # counted from 1, as shown to the person
    pcm: np.ndarray


class Enrolment:
    """The prompts, the checks on each recording, and the adaptation into a named voice profile."""

    def __init__(self, name: str, root: Path | None = None, prompts: Sequence[str] = PROMPTS) -> None:
        self.name = name
        self.folder = profile_dir(name, root)
        self.prompts = tuple(prompts)
        self._listener: PromptListener | None = None

    def prompt(self, number: int) -> str:
        return self.prompts[number - 1]

    def problem(self, recording: Recording) -> str | None:
        """Why a recording cannot be used for its prompt, or None when it can."""
        pcm = recording.pcm
        if seconds(pcm) < MIN_RECORDING_S:
            return f"too short ({seconds(pcm):.1f} s; the sentence takes longer to say)"
        verdict = judge(pcm)
        if not verdict.speech:
            return f"no speech in it: {verdict.reason}"
        if self._listener is None:
            self._listener = PromptListener(self.prompts)
        heard = self._listener.heard(padded(pcm))
        if heard in self.prompts and heard != self.prompt(recording.number):
            return f"it sounded like sentence {self.prompts.index(heard) + 1} ('{heard}')"
        return None

    def from_wav_dir(self, folder: Path) -> tuple[list[Recording], list[str]]:
        """The recordings ``prompt_01.wav`` ... in ``folder`` that pass their checks, and what is wrong with the rest."""
        if not folder.is_dir():
            raise EnrolmentError(f"no such folder: {folder}")
        missing = [prompt_file(n) for n in range(1, len(self.prompts) + 1) if not (folder / prompt_file(n)).is_file()]
        if len(missing) == len(self.prompts):
            raise EnrolmentError(
                f"{folder} has none of the recordings {prompt_file(1)} ... {prompt_file(len(self.prompts))} "
                "('hfpbd speech enrol --list' prints the sentence of each)"
            )
        usable: list[Recording] = []
        problems = [f"{name}: missing" for name in missing]
        for number in range(1, len(self.prompts) + 1):
            path = folder / prompt_file(number)
            if not path.is_file():
                continue
            try:
                recording = Recording(number, read_wav(path))
            except AudioError as exc:
                problems.append(f"{path.name}: {exc}")
                continue
            problem = self.problem(recording)
            if problem is None:
                usable.append(recording)
            else:
                problems.append(f"{path.name}: {problem}")
        return usable, problems

    def adapt(self, recordings: list[Recording], work: Path | None = None) -> Adaptation:
        """Estimate the voice's transform from ``recordings``, keep them in the profile, and write the transform."""
        if len(recordings) < MIN_USABLE:
            raise EnrolmentError(
                f"only {len(recordings)} of the {len(self.prompts)} sentences could be used; "
                f"at least {MIN_USABLE} are needed (record the others again)"
            )
        readings = [Reading(f"prompt {r.number}", self.prompt(r.number), padded(r.pcm)) for r in recordings]
        try:
            adaptation = solve_mllr(readings, self.folder / MATRIX_FILE, work)
        except AdaptationError as exc:
            raise EnrolmentError(str(exc)) from None
        kept = self.folder / RECORDINGS
        kept.mkdir(parents=True, exist_ok=True)
        for recording in recordings:
            write_wav(kept / prompt_file(recording.number), recording.pcm)
        return adaptation


def padded(pcm: np.ndarray) -> np.ndarray:
    """``pcm`` between short silences: both the checking decoder and bw expect silence before and after a sentence."""
    return np.concatenate([silence(PAD_S), pcm, silence(PAD_S)])


def listen(device: str | None, tell: Callable[[str], None], listen_s: float = LISTEN_S) -> np.ndarray | None:
    """One reading from the microphone: from the first speech until a pause of :data:`PAUSE_END_S`; None if nothing.

    Why not the first utterance the voice activity detector reports: people
    pause within a sentence they read, and a pause splits it.
    """
    blocks: queue.Queue[np.ndarray] = queue.Queue()
    try:
        microphone = Microphone(blocks.put, device)
    except MicrophoneUnavailable as exc:
        raise EnrolmentError(f"{exc}; record the sentences elsewhere and enrol with --wav-dir") from None
    splitter = UtteranceSplitter()
    heard: list[np.ndarray] = []
    quiet_s = 0.0
    started = time.monotonic()
    try:
        while time.monotonic() - started < listen_s:
            try:
                block = blocks.get(timeout=1.0)
            except queue.Empty:
                continue
            heard += splitter.feed(block)
            quiet_s = 0.0 if splitter.in_speech or not heard else quiet_s + len(block) / RATE
            if heard and quiet_s >= PAUSE_END_S:
                break
        heard += splitter.flush()
    finally:
        microphone.close()
    if not heard:
        tell("  (heard nothing)")
        return None
    return np.concatenate(heard)


def from_microphone(enrolment: Enrolment, device: str | None, tell: Callable[[str], None]) -> list[Recording]:
    """Prompt each sentence in turn and record it, asking again (up to :data:`ATTEMPTS` times) when it cannot be used."""
    usable = []
    total = len(enrolment.prompts)
    tell(f"Read each sentence aloud after it appears, in your usual voice, then pause. {total} sentences.")
    for number in range(1, total + 1):
        for attempt in range(1, ATTEMPTS + 1):
            again = " (again)" if attempt > 1 else ""
            tell(f"[{number}/{total}]{again} Say: {enrolment.prompt(number)}")
            pcm = listen(device, tell)
            if pcm is None:
                continue
            recording = Recording(number, pcm)
            problem = enrolment.problem(recording)
            if problem is None:
                usable.append(recording)
                break
            tell(f"  Not used: {problem}.")
        else:
            tell(f"  Skipping sentence {number} after {ATTEMPTS} tries.")
    return usable


def main(argv: Sequence[str]) -> int:
    parser = argparse.ArgumentParser(
        prog="hfpbd speech enrol",
        description="Read the prompted sentences aloud; the recogniser adapts to your voice (MLLR, SphinxTrain).",
    )
    parser.add_argument("--name", default=DEFAULT_NAME, help=f"the voice's name (default {DEFAULT_NAME!r})")
    parser.add_argument(
        "--wav-dir",
        type=Path,
        default=None,
        help="read prompt_01.wav ... from this folder instead of recording from the microphone",
    )
    parser.add_argument("--device", default=None, help="input device name or number (default: the system's)")
    parser.add_argument(
        "--voices-dir",
        type=Path,
        default=None,
        help=f"where voice profiles are kept (default {voices_dir()})",
    )
    parser.add_argument("--work-dir", type=Path, default=None, help="keep SphinxTrain's files and logs here")
    parser.add_argument("--list", action="store_true", help="print the sentences and their file names, and stop")
    args = parser.parse_args(argv)
    if args.list:
        for number, text in enumerate(PROMPTS, 1):
            print(f"{prompt_file(number)}  {text}")
        return 0
    try:
        enrolment = Enrolment(args.name, args.voices_dir)
        if args.wav_dir is not None:
            recordings, problems = enrolment.from_wav_dir(args.wav_dir)
            for problem in problems:
                print(f"hfpbd speech enrol: not used: {problem}", file=sys.stderr)
        else:
            recordings = from_microphone(enrolment, args.device, print)
        adaptation = enrolment.adapt(recordings, args.work_dir)
    except EnrolmentError as exc:
        print(f"hfpbd speech enrol: {exc}", file=sys.stderr)
        return 1
    if adaptation.unaligned:
        print(
            f"hfpbd speech enrol: left out, their audio did not fit their sentence: {', '.join(adaptation.unaligned)}",
            file=sys.stderr,
        )
    print(
        f"Enrolled voice {args.name!r} from {len(adaptation.aligned)} of {len(PROMPTS)} sentences "
        f"({adaptation.frames / 100:.0f} s of speech): {adaptation.matrix}"
    )
    print(f"Use it with: hfpbd speech --speaker {args.name}")
    return 0
