"""``hfpbd bench speech``: spoken commands and non-speech -> speech gate -> PocketSphinx -> NLU decision.

What it counts. Each spoken command ends one of four ways, as the services
would end it (:func:`services.speech.gate.judge`, the recogniser, then
:func:`services.nlu.nbest.choose` and :meth:`Choice.decision`): *right* (acted
on, and it is what was meant; a question answered on its topic), *wrong*
(acted on, and it is not), *asked* ("Did you say ...?", or the NLU's own
question back) and *not caught* (nothing moves; the user says it again).
Non-speech is streamed through the voice activity detector like microphone
audio, and every utterance found in it is judged the same way: a command
acted on is a *false acceptance*. Decoding time is CPU seconds per second of
audio, gate included, for speech and for non-speech.

The tuning set (the default) is the corpus (:mod:`services.speech.corpus`)
in espeak-ng's tuning voices and speeds, clean and in pink noise at 20 dB
and white noise at 25 dB signal-to-noise ratio, and non-speech of every kind
of :mod:`services.speech.sounds` from seeds 0 up. The thresholds of the
gate and of the decision were chosen on it (``--sweep`` prints the decision
thresholds' trade-off).

The held-out set (``--held-out``) is never tuned on: the same sentences
spoken by other talkers -- Flite's kal, awb, rms and slt voices at 90, 100
and 120 per cent of their normal length (another synthesiser) and
espeak-ng's held-out voices and speeds -- clean, in brown noise at 15 dB,
in quiet babble at 15 dB and in white noise at 20 dB (noise kinds and
levels not used for tuning), and non-speech from seeds 10000 up.

With ``--enrolled`` the same audio is heard again after each talker has
enrolled its voice (:mod:`services.speech.bench_enrolled`), and the two runs
are printed side by side; the exit status then says whether the enrolled
run met the targets, since that is the condition being asked about.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections import Counter
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from services.nlu.infer import Clarify, CommandResult, Model, Result
from services.nlu.nbest import ACT_SHARE, CONFIRM_SHARE, Choice, Decision, Reading, choose
from services.nlu.results import Answer
from services.nlu.world import parse_world
from services.speech import espeak, sounds
from services.speech.adapt import AdaptationError, find_tools
from services.speech.audio import RATE, same_audio, silence
from services.speech.corpus import HELD_OUT_SPEEDS, HELD_OUT_VOICES, SCENES, STATES, VOICES, Item, corpus
from services.speech.gate import judge
from services.speech.grammar import SceneWords
from services.speech.recogniser import PER_MEANING, Recogniser
from services.speech.synthesisers import FLITE, Talker, available
from services.speech.vad import UtteranceSplitter
from services.speech.vocabulary import nlu_vocabulary

Noise = tuple[str, float] | None  # (kind of sounds.KINDS, signal-to-noise ratio in dB), or clean
TUNING_NOISE: tuple[Noise, ...] = (None, ("pink noise", 20.0), ("white noise", 25.0))
HELD_OUT_NOISE: tuple[Noise, ...] = (None, ("brown noise", 15.0), ("babble", 15.0), ("white noise", 20.0))
HELD_OUT_TALKERS = tuple(Talker(FLITE, v, s) for v in ("kal", "awb", "rms", "slt") for s in (90, 100, 120)) + tuple(
    Talker(espeak.ESPEAK, v, s) for v, s in zip(HELD_OUT_VOICES, HELD_OUT_SPEEDS * 2)
)
HELD_OUT_SEED = 10_000
ACT_SHARES = (0.5, 0.7, 0.8, 0.9, 0.95)
CONFIRM_SHARES = (0.1, 0.2, 0.3, 0.5)
TARGET_RIGHT, TARGET_WRONG = 0.95, 0.01
NON_SPEECH_SCENE = "cups"
SPEECH_OUTCOMES = ("right", "wrong", "asked", "not caught")


@dataclass
class Heard:
    """One utterance through the whole chain, kept so that the decision can be re-run at other thresholds."""

    talker: str
    noise: str
    expected: dict[str, Any] | None  # None: not a command (non-speech)
    choice: Choice | None  # None: gated out or nothing heard
    seconds: float
    cpu_s: float


def meaning(result: Result) -> dict | None:
    """What a reading means, in the corpus's terms: the command and its further steps, or the question's topic."""
    if isinstance(result, Answer):
        return {"answer": result.topic}
    if not isinstance(result, CommandResult):
        return None
    meaning = result.command.as_dict()
    if result.then:
        meaning["then"] = [c.as_dict() for c in result.then]
    return meaning


def outcome(heard: Heard, act: float = ACT_SHARE, confirm: float = CONFIRM_SHARE) -> str:
    """right, wrong, asked or not caught (for non-speech: acted, answered, asked or ignored)."""
    choice = heard.choice
    if choice is None:
        return "not caught" if heard.expected is not None else "ignored"
    decision = choice.decision(act, confirm)
    result = choice.reading.result
    if decision is Decision.REJECT:
        return "not caught" if heard.expected is not None else "ignored"
    if decision is Decision.CONFIRM or isinstance(result, Clarify):
        return "asked"
    if heard.expected is None:
        return "acted" if isinstance(result, CommandResult) else "answered"
    return "right" if meaning(result) == heard.expected else "wrong"


class Listener:
    """The chain under test: gate, recogniser, NLU choice, with the scene set per utterance."""

    def __init__(self, vocabulary: str, mllr: Path | None = None) -> None:
        """``mllr``: a talker's enrolled transform (``hfpbd speech enrol``), as ``hfpbd speech --speaker`` loads it."""
        per_meaning = None if vocabulary == "full" else PER_MEANING
        self.recogniser = Recogniser(nlu_vocabulary(), per_meaning=per_meaning, mllr=mllr)
        self._models: dict[str, Model] = {}

    def hear(
        self, pcm: np.ndarray, world: dict[str, Any], key: str, only_stop: bool = False
    ) -> tuple[Choice | None, float]:
        """The NLU's choice for one utterance (None when gated out or nothing heard) and the CPU seconds taken.

        ``only_stop``: an utterance offered early, which the service sends on
        only when sentences that say nothing but stop hold the share the NLU
        acts on a stop at (else None).
        """
        if key not in self._models:
            self._models[key] = Model(parse_world(world))
        model = self._models[key]
        self.recogniser.set_scene(SceneWords.of(world["objects"]))
        started = time.process_time()
        hypotheses = self.recogniser.decode(pcm) if judge(pcm).speech else []
        cpu = time.process_time() - started
        if only_stop and not self.recogniser.heard_stop(hypotheses):
            return None, cpu
        readings = [Reading(h.text, h.score, model.parse(h.text), h.first) for h in hypotheses if h.score > 0]
        return choose(readings), cpu


def _noise_name(noise: Noise) -> str:
    return "clean" if noise is None else f"{noise[0]} {noise[1]:g} dB"


def speech_set(held_out: bool, limit: int | None) -> list[tuple[Item, Talker, Noise]]:
    """The spoken commands: each corpus sentence with a talker and a noise condition, rotating."""
    items = corpus()[:limit]
    noises = HELD_OUT_NOISE if held_out else TUNING_NOISE
    cycle = len(HELD_OUT_TALKERS) if held_out else len(VOICES)  # each talker meets every noise in turn
    chosen = []
    for n, item in enumerate(items):
        talker = HELD_OUT_TALKERS[n % cycle] if held_out else Talker(espeak.ESPEAK, item.voice, item.speed)
        chosen.append((item, talker, noises[(n // cycle) % len(noises)]))
    return chosen


@dataclass(frozen=True)
class Spoken:
    """One spoken command as the microphone hears it, made once so that every listener compared hears the same."""

    item: Item
    talker: Talker
    noise: Noise
    pcm: np.ndarray


def recorded(chosen: list[tuple[Item, Talker, Noise]], seed: int) -> list[Spoken]:
    """Each command said by its talker between short silences, in its noise, cut at a random sample to start."""
    spoken = []
    rng = np.random.default_rng(seed)
    for n, (item, talker, noise) in enumerate(chosen):
        pcm = np.concatenate([silence(0.3), talker.say(item.text), silence(0.3)])
        if noise is not None:
            pcm = sounds.mixed(pcm, sounds.sound(noise[0], seed + n, len(pcm) / RATE + 0.5), noise[1])
        pcm = pcm[int(rng.integers(0, 160)) :]  # not always on a frame boundary
        spoken.append(Spoken(item, talker, noise, pcm))
    return spoken


def run_speech(listener: Listener, spoken: Iterable[Spoken]) -> list[Heard]:
    heard = []
    for s in spoken:
        choice, cpu = listener.hear(s.pcm, s.item.world, f"{s.item.scene}/{s.item.world['robot']}")
        heard.append(Heard(s.talker.name, _noise_name(s.noise), s.item.expected, choice, len(s.pcm) / RATE, cpu))
    return heard


def run_non_speech(listener: Listener, minutes: float, seed: int) -> list[Heard]:
    """At least ``minutes`` of every kind of non-speech together, streamed as a microphone would send it."""
    world = {"objects": SCENES[NON_SPEECH_SCENE][0], "robot": STATES["right"]}
    heard = []
    per_kind = minutes * 60 / len(sounds.KINDS)
    for kind in sounds.KINDS:
        total, n = 0.0, 0
        while total < per_kind:
            pcm = np.concatenate([silence(0.5), sounds.sound(kind, seed + n, 3.0), silence(0.8)])
            n += 1
            total += len(pcm) / RATE
            splitter = UtteranceSplitter()
            utterances: list[np.ndarray] = []
            offers: list[np.ndarray] = []
            for start in range(0, len(pcm), RATE // 10):
                utterances += splitter.feed(pcm[start : start + RATE // 10])
                offer = splitter.candidate
                if offer is not None and not (offers and len(offers[-1]) == len(offer)):
                    offers.append(offer)
            utterances += splitter.flush()
            seconds = len(pcm) / RATE
            for utterance in utterances:
                choice, cpu = listener.hear(utterance, world, NON_SPEECH_SCENE)
                heard.append(Heard(kind, kind, None, choice, seconds / len(utterances), cpu))
            if not utterances:
                heard.append(Heard(kind, kind, None, None, seconds, 0.0))
            heard += early_stops(
                listener, world, [o for o in offers if not any(same_audio(o, u) for u in utterances)], kind
            )
    return heard


def early_stops(listener: Listener, world: dict[str, Any], withdrawn: list[np.ndarray], kind: str) -> list[Heard]:
    """The stops the service would have sent from offers withdrawn later (the sound went on): each one heard.

    An offer that became an utterance is heard as that utterance; one that did
    not is decoded by the service only while it is idle, so this is at most.
    """
    heard = []
    for offer in withdrawn:
        choice, cpu = listener.hear(offer, world, NON_SPEECH_SCENE, only_stop=True)
        if choice is not None:
            heard.append(Heard(kind, kind, None, choice, 0.0, cpu))
    return heard


def grouped(heard: list[Heard], by: str) -> list[tuple[str, list[Heard]]]:
    """``heard`` by talker or noise (the field ``by`` of :class:`Heard`), sorted by name, then all of it."""
    groups: dict[str, list[Heard]] = {}
    for h in heard:
        groups.setdefault(getattr(h, by), []).append(h)
    return [*sorted(groups.items()), ("all", heard)]


def _table(title: str, heard: list[Heard], by: str, columns: tuple[str, ...]) -> None:
    print(f"  {title:<28} {'n':>4} " + " ".join(f"{c:>10}" for c in columns))
    for name, members in grouped(heard, by):
        counts = Counter(outcome(h) for h in members)
        print(f"  {name:<28} {len(members):>4} " + " ".join(f"{counts[c]:>10}" for c in columns))


def _cpu(heard: list[Heard]) -> str:
    rates = [h.cpu_s / h.seconds for h in heard if h.seconds > 0]
    total = sum(h.cpu_s for h in heard) / max(1e-9, sum(h.seconds for h in heard))
    return (
        f"{total:.3f} s per s overall, per utterance mean {statistics.mean(rates):.3f}, "
        f"p95 {float(np.percentile(rates, 95)):.3f}, max {max(rates):.3f} ({sum(h.seconds for h in heard):.0f} s of audio)"
    )


def report(speech: list[Heard], non_speech: list[Heard], title: str, sweep: bool) -> bool:
    print(f"{title}: {len(speech)} spoken commands, {sum(h.seconds for h in non_speech) / 60:.1f} min of non-speech")
    if speech:
        _table("talker", speech, "talker", SPEECH_OUTCOMES)
        _table("condition", speech, "noise", SPEECH_OUTCOMES)
    counts = Counter(outcome(h) for h in speech)
    n = max(1, len(speech))
    right, wrong = counts["right"] / n, counts["wrong"] / n
    print(
        f"  carried out as meant {right:.1%} (target >= {TARGET_RIGHT:.0%}), wrongly {wrong:.1%} "
        f"(target <= {TARGET_WRONG:.0%}), asked {counts['asked'] / n:.1%}, not caught {counts['not caught'] / n:.1%}"
    )
    asked_right = sum(
        outcome(h) == "asked" and h.choice is not None and meaning(h.choice.reading.result) == h.expected
        for h in speech
    )
    print(f"  questions asked about the command meant: {asked_right} of {counts['asked']}")
    if sweep and speech:
        print("  decision thresholds (act share / confirm share): right, wrong, asked, not caught")
        for act in ACT_SHARES:
            for confirm in CONFIRM_SHARES:
                c = Counter(outcome(h, act, confirm) for h in speech)
                mark = "  <- chosen" if (act, confirm) == (ACT_SHARE, CONFIRM_SHARE) else ""
                print(
                    f"    {act:<4g} / {confirm:<4g}  {c['right']:>4} {c['wrong']:>4} {c['asked']:>4} "
                    f"{c['not caught']:>4}{mark}"
                )
    acted = sum(outcome(h) == "acted" for h in non_speech)
    if non_speech:
        _table("non-speech", non_speech, "talker", ("acted", "answered", "asked", "ignored"))
        print(f"  false acceptances (a command acted on): {acted} in {sum(h.seconds for h in non_speech) / 60:.1f} min")
        for h in non_speech:
            if outcome(h) in ("acted", "answered", "asked") and h.choice is not None:
                print(f"    {h.talker}: {outcome(h)} {h.choice.reading.text!r}")
    if speech:
        print(f"  decoding CPU, speech:     {_cpu(speech)}")
    if non_speech:
        print(f"  decoding CPU, non-speech: {_cpu(non_speech)}")
    for h in speech:
        if outcome(h) == "wrong" and h.choice is not None:
            print(f"  wrong [{h.talker}, {h.noise}] meant {h.expected}, heard {h.choice.reading.text!r}")
    return right >= TARGET_RIGHT and wrong <= TARGET_WRONG and acted == 0


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="hfpbd bench speech", description=__doc__.splitlines()[0])
    parser.add_argument("--vocabulary", choices=("core", "full"), default="core")
    parser.add_argument("--limit", type=int, default=None, help="only the first N sentences of the corpus")
    parser.add_argument("--non-speech-minutes", type=float, default=10.0, help="minutes of non-speech (default 10)")
    parser.add_argument("--held-out", action="store_true", help="the held-out talkers, noises and sounds")
    parser.add_argument("--sweep", action="store_true", help="print the decision thresholds' trade-off")
    parser.add_argument(
        "--enrolled",
        action="store_true",
        help="then again with each talker enrolled first (hfpbd speech enrol), and both side by side",
    )
    args = parser.parse_args(argv)
    for program, package in ((espeak.ESPEAK, "espeak-ng"), *([(FLITE, "flite")] if args.held_out else [])):
        if not available(program):
            print(f"hfpbd bench speech: {program} is not installed (Debian package {package})", file=sys.stderr)
            return 2
    if args.enrolled:
        try:
            find_tools()
        except AdaptationError as exc:
            print(f"hfpbd bench speech: {exc}", file=sys.stderr)
            return 2
    seed = HELD_OUT_SEED if args.held_out else 0
    title = "held-out set" if args.held_out else "tuning set"
    spoken = recorded(speech_set(args.held_out, args.limit), seed)
    listener = Listener(args.vocabulary)
    speech = run_speech(listener, spoken)
    non_speech = run_non_speech(listener, args.non_speech_minutes, seed)
    met = report(speech, non_speech, title, args.sweep)
    if not args.enrolled:
        return 0 if met else 1
    from services.speech.bench_enrolled import compare, run_enrolled  # it builds on this module

    enrolled, enrolled_non_speech, voice = run_enrolled(args.vocabulary, spoken, args.non_speech_minutes, seed)
    print()
    met = report(enrolled, enrolled_non_speech, f"{title}, each talker enrolled (non-speech: {voice})", args.sweep)
    print()
    compare(speech, enrolled, non_speech, enrolled_non_speech)
    return 0 if met else 1
