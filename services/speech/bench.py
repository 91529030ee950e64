"""``hfpbd bench speech``: espeak-ng corpus -> PocketSphinx -> NLU, in fixed scenes.

Reports word error rate, command accuracy (a question counts as right when
it is answered on its topic; a compound when every step is right) from the top hypothesis and from
the n-best rescored by the NLU (:func:`services.nlu.nbest.choose`, the NLU
service's own rule, on each hypothesis parsed once), how many commands it would not act on for too
little support in the n-best and the accuracy among the rest, and decoding
time per second of audio. The rescoring is shown for several acoustic
scales, off-grammar priors, NLU weights and rejection thresholds; these are
chosen with ``--held-out`` (other voices and speeds), not on the benchmark.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from rapidfuzz.distance import Levenshtein

from services.nlu.infer import CommandResult, Model, Result
from services.nlu.nbest import NLU_WEIGHT, REJECT_BELOW, Choice, Reading, choose
from services.nlu.results import Answer
from services.nlu.world import parse_world
from services.speech import espeak
from services.speech.audio import RATE, read_wav, silence
from services.speech.corpus import PAPER, Item, corpus, held_out
from services.speech.grammar import SceneWords
from services.speech.recogniser import (
    ACOUSTIC_SCALE,
    COMPOUND_PRIOR,
    OFF_GRAMMAR_PRIOR,
    PER_MEANING,
    Hypothesis,
    Recogniser,
    posteriors,
)
from services.speech.vocabulary import nlu_vocabulary

SCALES = (0.0, 0.01, 0.03, 0.1, 0.3, 1.0)
OFF_GRAMMAR_PRIORS = (1.0, 0.3, 0.1, 0.03, 0.01)
COMPOUND_PRIORS = (1.0, 0.5, 0.3, 0.1, 0.03)
NLU_WEIGHTS = (0.02, 0.05, 0.1, 0.2, 0.5, 1.0)
REJECTION_THRESHOLDS = (0.03, 0.05, 0.1, 0.2, 0.3)
TARGET_ACCURACY = 0.90


@dataclass
class Outcome:
    item: Item
    hypotheses: list[Hypothesis]
    seconds: float
    decode_s: float
    results: list[Result] = field(default_factory=list)


def _words(text: str) -> list[str]:
    return text.lower().replace(",", " ").split()


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


def rescored(
    outcome: Outcome,
    scale: float = ACOUSTIC_SCALE,
    off_grammar: float = OFF_GRAMMAR_PRIOR,
    nlu_weight: float = NLU_WEIGHT,
    compound: float = COMPOUND_PRIOR,
) -> Choice | None:
    """The NLU's choice from the n-best as the speech service would send it at these weights."""
    members = {h.text for h in outcome.hypotheses if h.in_grammar}
    results = {h.text: r for h, r in zip(outcome.hypotheses, outcome.results)}
    nbest = posteriors({h.text: h.loglik for h in outcome.hypotheses}, scale, members, off_grammar, compound)
    return choose((Reading(h.text, h.score, results[h.text]) for h in nbest if h.score > 0), nlu_weight)


def _right(outcome: Outcome, choice: Choice | None) -> bool:
    return choice is not None and meaning(choice.reading.result) == outcome.item.expected


def _rejections(outcomes: list[Outcome], choices: list[Choice | None], below: float) -> str:
    """How many commands would not be acted on, how many of them wrongly, and the accuracy among the rest."""
    rejected = [choice is not None and choice.rejected(below) for choice in choices]
    wrong = sum(r and not _right(o, c) for o, c, r in zip(outcomes, choices, rejected))
    rest = [_right(o, c) for o, c, r in zip(outcomes, choices, rejected) if not r]
    return (
        f"{sum(rejected)} not acted on ({wrong} of them wrong); "
        f"accuracy among the rest {sum(rest) / max(1, len(rest)):.2%}"
    )


def run(items: list[Item], vocabulary: str, out: Path) -> list[Outcome]:
    recogniser = Recogniser(nlu_vocabulary(), per_meaning=None if vocabulary == "full" else PER_MEANING)
    outcomes: list[Outcome] = []
    for n, item in enumerate(items):
        path = out / f"{n:03d}.wav"
        espeak.write(item.text, path, item.voice, item.speed)
        pcm = np.concatenate([silence(0.3), read_wav(path), silence(0.3)])
        recogniser.set_scene(SceneWords.of(item.world["objects"]))
        started = time.perf_counter()
        hypotheses = recogniser.decode(pcm, acoustic_scale=0.0)  # keep every alternative; re-weighted below
        decode_s = time.perf_counter() - started
        model = Model(parse_world(item.world))
        outcome = Outcome(item, hypotheses, len(pcm) / RATE, decode_s, [model.parse(h.text) for h in hypotheses])
        outcomes.append(outcome)
    return outcomes


def report(outcomes: list[Outcome], vocabulary: str, title: str = "speech benchmark") -> bool:
    n = len(outcomes)
    errors = sum(
        Levenshtein.distance(_words(o.item.text), _words(o.hypotheses[0].text if o.hypotheses else ""))
        for o in outcomes
    )
    reference_words = sum(len(_words(o.item.text)) for o in outcomes)
    exact = sum(bool(o.hypotheses) and o.hypotheses[0].text == o.item.text for o in outcomes)
    top1 = sum(bool(o.results) and meaning(o.results[0]) == o.item.expected for o in outcomes)
    in_nbest = sum(any(meaning(r) == o.item.expected for r in o.results) for o in outcomes)
    rtf = [o.decode_s / o.seconds for o in outcomes]
    audio = sum(o.seconds for o in outcomes)
    print(
        f"{title}: {n} utterances, {len({o.item.expected.get('procedure', 'answer') for o in outcomes})} meanings, "
        f"{len({o.item.scene for o in outcomes})} scenes, {len({o.item.voice for o in outcomes})} voices, "
        f"{len({o.item.speed for o in outcomes})} speeds; grammar: {vocabulary} vocabulary"
    )
    print(
        f"  word error rate (top hypothesis)         {errors / reference_words:7.2%}  ({errors} errors / {reference_words} words)"
    )
    print(f"  sentence exactly right                   {exact / n:7.2%}")
    print(f"  command accuracy, top hypothesis         {top1 / n:7.2%}")
    for scale in SCALES:
        accuracy = sum(_right(o, rescored(o, scale)) for o in outcomes) / n
        mark = "  <- ACOUSTIC_SCALE" if scale == ACOUSTIC_SCALE else ""
        print(f"  command accuracy, n-best rescored @{scale:<5g} {accuracy:7.2%}{mark}")
    for prior in OFF_GRAMMAR_PRIORS:
        accuracy = sum(_right(o, rescored(o, off_grammar=prior)) for o in outcomes) / n
        mark = "  <- OFF_GRAMMAR_PRIOR" if prior == OFF_GRAMMAR_PRIOR else ""
        print(f"  ... n-gram-only sentences weighted {prior:<5g} {accuracy:7.2%}{mark}")
    for prior in COMPOUND_PRIORS:
        accuracy = sum(_right(o, rescored(o, compound=prior)) for o in outcomes) / n
        mark = "  <- COMPOUND_PRIOR" if prior == COMPOUND_PRIOR else ""
        print(f"  ... two-step sentences weighted {prior:<5g}      {accuracy:7.2%}{mark}")
    for weight in NLU_WEIGHTS:
        accuracy = sum(_right(o, rescored(o, nlu_weight=weight)) for o in outcomes) / n
        mark = "  <- NLU_WEIGHT" if weight == NLU_WEIGHT else ""
        print(f"  ... NLU score weighted {weight:<5g}             {accuracy:7.2%}{mark}")
    choices = [rescored(o) for o in outcomes]
    for below in REJECTION_THRESHOLDS:
        mark = "  <- REJECT_BELOW" if below == REJECT_BELOW else ""
        print(f"  ... share of the n-best < {below:<5g}: {_rejections(outcomes, choices, below)}{mark}")
    print(f"  right command anywhere in the n-best     {in_nbest / n:7.2%}")
    print(f"  n-best length                            mean {statistics.mean(len(o.hypotheses) for o in outcomes):.2f}")
    print(
        f"  decode time per second of audio          mean {statistics.mean(rtf):.3f} s, "
        f"p95 {float(np.percentile(rtf, 95)):.3f} s, max {max(rtf):.3f} s ({audio:.0f} s of audio)"
    )
    for category in dict.fromkeys(o.item.category for o in outcomes):
        kept = [(o, c) for o, c in zip(outcomes, choices) if o.item.category == category]
        right = sum(_right(o, c) for o, c in kept)
        label = "the paper's commands" if category == PAPER else f"new form: {category}"
        print(f"  ... {label:<37} {right / len(kept):7.2%}  ({right}/{len(kept)})")
    best = sum(_right(o, c) for o, c in zip(outcomes, choices)) / n
    print(f"  command accuracy, n-best rescored        {best:7.2%}; {_rejections(outcomes, choices, REJECT_BELOW)}")
    print(f"  target command accuracy >= {TARGET_ACCURACY:.0%}: {'met' if best >= TARGET_ACCURACY else 'NOT met'}")
    for o, c in zip(outcomes, choices):
        if not _right(o, c):
            print(
                f"  miss [{o.item.voice} {o.item.speed}]{' (not acted on)' if c is not None and c.rejected() else ''} "
                f"said {o.item.text!r}, heard {[h.text for h in o.hypotheses] or 'nothing'}"
            )
    return best >= TARGET_ACCURACY


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="hfpbd bench speech", description=__doc__.splitlines()[0])
    parser.add_argument("--vocabulary", choices=("core", "full"), default="core")
    parser.add_argument("--limit", type=int, default=None, help="only the first N utterances")
    parser.add_argument(
        "--held-out",
        action="store_true",
        help="the held-out set (other voices and speeds) on which the weights are chosen",
    )
    args = parser.parse_args(argv)
    if not espeak.available():
        print("hfpbd bench speech: espeak-ng is not installed (Debian package espeak-ng)", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory(prefix="hfpbd-speech-bench-") as folder:
        outcomes = run((held_out() if args.held_out else corpus())[: args.limit], args.vocabulary, Path(folder))
    return 0 if report(outcomes, args.vocabulary, "held-out set" if args.held_out else "speech benchmark") else 1
