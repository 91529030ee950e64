"""``hfpbd bench enrol``: how much voice enrolment helps, on sentences the voice did not read.

For each synthetic talker (Flite voices and espeak-ng variants, some slower
and some faster than usual) the benchmark does what a person does with
``hfpbd speech enrol``: the talker reads the prompted sentences
(:data:`services.speech.prompts.PROMPTS`), the readings are checked and an
MLLR transform is estimated from them. Then the same talker says sentences
of the speech corpus (:mod:`services.speech.corpus`) -- none of them a
prompt -- and each is decoded by the recogniser as the speech service runs
it (grammar of the sentence's scene, n-gram pass), once with the shipped
model and once adapted. Word accuracy is 1 - word error rate of the top
sentence; sentence accuracy counts top sentences that are exactly right.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from services.speech import espeak
from services.speech.bench_enrolled import enrol
from services.speech.corpus import Item, corpus
from services.speech.enrol import EnrolmentError, padded
from services.speech.grammar import SceneWords
from services.speech.prompts import PROMPTS
from services.speech.recogniser import Recogniser
from services.speech.synthesisers import FLITE, Talker, available
from services.speech.vocabulary import nlu_vocabulary

TALKERS = (
    Talker(FLITE, "kal", 100),
    Talker(FLITE, "awb", 120),  # Flite's speed is per cent of the normal length: 120 is slower
    Talker(FLITE, "slt", 85),
    Talker(espeak.ESPEAK, "en-us+f2", 130),
    Talker(espeak.ESPEAK, "en-029", 195),
    Talker(espeak.ESPEAK, "en-gb-x-gbclan", 180),
)
SENTENCES = 40


@dataclass
class Score:
    """Top sentences against what was said, for one talker and one model."""

    words: int = 0
    word_errors: int = 0
    sentences: int = 0
    right: int = 0

    def add(self, said: str, heard: str) -> None:
        self.words += len(said.split())
        self.word_errors += word_errors(said.split(), heard.split())
        self.sentences += 1
        self.right += said == heard

    def __iadd__(self, other: Score) -> Score:
        self.words += other.words
        self.word_errors += other.word_errors
        self.sentences += other.sentences
        self.right += other.right
        return self

    @property
    def word_accuracy(self) -> float:
        return 1.0 - self.word_errors / max(1, self.words)

    @property
    def sentence_accuracy(self) -> float:
        return self.right / max(1, self.sentences)


def word_errors(said: list[str], heard: list[str]) -> int:
    """Substitutions, deletions and insertions turning ``said`` into ``heard`` (Levenshtein over words)."""
    previous = list(range(len(heard) + 1))
    for i, word in enumerate(said, 1):
        current = [i]
        for j, other in enumerate(heard, 1):
            current.append(min(previous[j] + 1, current[j - 1] + 1, previous[j - 1] + (word != other)))
        previous = current
    return previous[-1]


def held_out(count: int) -> list[Item]:
    """``count`` corpus sentences spread over its scenes and forms, none of them a prompt."""
    items = [item for item in corpus() if item.text not in PROMPTS]
    step = max(1, len(items) // count)
    return items[::step][:count]


def score(recogniser: Recogniser, items: list[Item], audio: list[np.ndarray]) -> Score:
    result = Score()
    for item, pcm in zip(items, audio):
        recogniser.set_scene(SceneWords.of(item.world["objects"]))
        hypotheses = recogniser.decode(pcm)
        result.add(item.text, hypotheses[0].text if hypotheses else "")
    return result


def _row(name: str, used: str, before: Score, after: Score) -> str:
    return (
        f"  {name:<30} {used:>7}  {before.word_accuracy:6.1%} -> {after.word_accuracy:6.1%}"
        f"   {before.sentence_accuracy:6.1%} -> {after.sentence_accuracy:6.1%}"
    )


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="hfpbd bench enrol", description=__doc__.splitlines()[0])
    parser.add_argument("--sentences", type=int, default=SENTENCES, help=f"held-out sentences per talker ({SENTENCES})")
    parser.add_argument("--talkers", type=int, default=len(TALKERS), help="only the first N talkers")
    args = parser.parse_args(argv)
    for program, package in ((espeak.ESPEAK, "espeak-ng"), (FLITE, "flite")):
        if not available(program):
            print(f"hfpbd bench enrol: {program} is not installed (Debian package {package})", file=sys.stderr)
            return 2
    items = held_out(args.sentences)
    shipped = Recogniser(nlu_vocabulary())
    print(f"enrolment: {len(PROMPTS)} prompts read; {len(items)} other sentences decoded per talker, before -> after")
    print(f"  {'talker':<30} {'prompts':>7}  {'word accuracy':>17}   {'sentence accuracy':>17}")
    total_before, total_after = Score(), Score()
    for talker in TALKERS[: args.talkers]:
        with tempfile.TemporaryDirectory(prefix="hfpbd-bench-enrol-") as folder:
            try:
                adaptation = enrol(talker, Path(folder))
            except EnrolmentError as exc:
                print(f"  {talker.name:<30} enrolment failed: {exc}")
                continue
            adapted = Recogniser(nlu_vocabulary(), mllr=adaptation.matrix)
        audio = [padded(talker.say(item.text)) for item in items]
        before, after = score(shipped, items, audio), score(adapted, items, audio)
        total_before += before
        total_after += after
        print(_row(talker.name, f"{len(adaptation.aligned)}/{len(PROMPTS)}", before, after), flush=True)
    print(_row("all", "", total_before, total_after))
    return 0 if total_after.word_accuracy >= total_before.word_accuracy else 1
