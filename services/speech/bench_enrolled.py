"""``hfpbd bench speech --enrolled``: the same spoken commands again, each talker having enrolled its voice first.

Each talker of the speech set does what a person does with ``hfpbd speech
enrol``: it reads the prompted sentences (:data:`services.speech.prompts.PROMPTS`)
in clean audio, each reading is checked as the command checks a recording,
and an MLLR transform is estimated from those that pass
(:class:`services.speech.enrol.Enrolment`). Then the talker's commands --
the very audio of the plain run, so the same sentences, noises and seeds --
go through the same gate, recogniser and NLU decision, the recogniser
loading the talker's transform as ``hfpbd speech --speaker`` does. A talker
whose enrolment fails is decoded with the shipped model, as a person who
could not enrol would be.

Why non-speech is heard again: a transform moves the acoustic model towards
one voice, and it may move it towards some noise as well, so false
acceptances are counted with an enrolled recogniser too (the first
talker's transform; the service loads one speaker's at a time).
"""

from __future__ import annotations

import tempfile
from collections import Counter
from pathlib import Path

from services.speech.adapt import Adaptation
from services.speech.bench import SPEECH_OUTCOMES, Heard, Listener, Spoken, grouped, outcome, run_non_speech, run_speech
from services.speech.enrol import Enrolment, EnrolmentError, Recording
from services.speech.prompts import PROMPTS
from services.speech.synthesisers import Talker

Change = dict[str, tuple[int, int]]  # outcome -> (count un-enrolled, count enrolled)


def enrol(talker: Talker, root: Path) -> Adaptation:
    """The talker reads the prompts and is enrolled into ``root``; only readings that pass their checks are used."""
    enrolment = Enrolment("bench", root)
    readings = [Recording(n, talker.say(text)) for n, text in enumerate(PROMPTS, 1)]
    return enrolment.adapt([r for r in readings if enrolment.problem(r) is None])


def run_enrolled(
    vocabulary: str, spoken: list[Spoken], minutes: float, seed: int
) -> tuple[list[Heard], list[Heard], str]:
    """Each talker enrolled, then its commands heard; non-speech heard with the first transform, named last."""
    heard: list[Heard] = []
    talkers = list(dict.fromkeys(s.talker for s in spoken))  # in the order the plain run met them
    transforms: dict[Talker, Path] = {}  # each talker's, kept for the run in a temporary folder
    print(f"enrolling {len(talkers)} talkers ({len(PROMPTS)} prompts each, clean), then hearing their commands")
    with tempfile.TemporaryDirectory(prefix="hfpbd-bench-enrolled-") as folder:
        for n, talker in enumerate(talkers):
            try:
                adaptation = enrol(talker, Path(folder) / f"talker{n:02d}")
            except EnrolmentError as exc:
                print(f"  {talker.name:<28} enrolment failed, heard with the shipped model: {exc}", flush=True)
            else:
                transforms[talker] = adaptation.matrix
                left_out = f", left out by alignment: {', '.join(adaptation.unaligned)}" if adaptation.unaligned else ""
                print(
                    f"  {talker.name:<28} enrolled from {len(adaptation.aligned)}/{len(PROMPTS)} prompts "
                    f"({adaptation.frames / 100:.0f} s of speech){left_out}",
                    flush=True,
                )
            heard += run_speech(Listener(vocabulary, transforms.get(talker)), [s for s in spoken if s.talker == talker])
        first = next(iter(transforms), None)
        non_speech = run_non_speech(Listener(vocabulary, transforms[first] if first else None), minutes, seed)
    return heard, non_speech, f"{first.name}'s transform" if first else "no talker enrolled, shipped model"


def changes(plain: list[Heard], enrolled: list[Heard], by: str) -> list[tuple[str, int, Change]]:
    """Per talker or noise (``by``) and overall: how many utterances, and each outcome's count without and with."""
    after = dict(grouped(enrolled, by))
    rows = []
    for name, members in grouped(plain, by):
        before_counts = Counter(outcome(h) for h in members)
        after_counts = Counter(outcome(h) for h in after.get(name, []))
        rows.append((name, len(members), {o: (before_counts[o], after_counts[o]) for o in SPEECH_OUTCOMES}))
    return rows


def compare(
    plain: list[Heard], enrolled: list[Heard], plain_non_speech: list[Heard], enrolled_non_speech: list[Heard]
) -> None:
    """The two runs side by side: each outcome's count un-enrolled -> enrolled."""
    print("un-enrolled -> enrolled")
    for title, by in (("talker", "talker"), ("condition", "noise")):
        print(f"  {title:<28} {'n':>4} " + " ".join(f"{o:>12}" for o in SPEECH_OUTCOMES))
        for name, n, change in changes(plain, enrolled, by):
            cells = " ".join(f"{f'{a} -> {b}':>12}" for a, b in (change[o] for o in SPEECH_OUTCOMES))
            print(f"  {name:<28} {n:>4} {cells}")
    _, n, overall = changes(plain, enrolled, "talker")[-1]  # the row of all of them
    print("  " + ", ".join(f"{o} {a / max(1, n):.1%} -> {b / max(1, n):.1%}" for o, (a, b) in overall.items()))
    acted = [sum(outcome(h) == "acted" for h in run) for run in (plain_non_speech, enrolled_non_speech)]
    minutes = [sum(h.seconds for h in run) / 60 for run in (plain_non_speech, enrolled_non_speech)]
    print(f"  non-speech false acceptances: {acted[0]} in {minutes[0]:.1f} min -> {acted[1]} in {minutes[1]:.1f} min")
