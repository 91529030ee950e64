"""Offline decoding with PocketSphinx: a grammar pass and an n-gram pass, pooled into an n-best list.

Why n-best: the top string is often one word off ("left" for "right"); the
NLU can pick the alternative that makes sense in the scene (P(C|S)) when it
sees the runners-up and how much less likely the recogniser found them.

Why two passes: a grammar search yields a single path, so its "n-best" is
nearly always one sentence. The same audio decoded under an n-gram model of
the command language (full vocabulary, no scene restriction) gives
genuinely different readings ("raise your arm" where the grammar heard
"bring the left arm"); both passes score with the same acoustic model, so
their scores can be pooled.

Why the passes' first choices are kept: the two searches are differently
constrained (the scene's sentences against any word sequence of the command
language), so when both put the same meaning first the audio fits it
however it is searched, and when they differ the recogniser is guessing.
The NLU acts only on such agreement (``services.nlu.nbest``); the count of
first choices travels with each hypothesis (``first``).

Why one front end at 100 frames per second and PocketSphinx's default four
Gaussians per frame: decoding must keep up with speech on a small machine
(at most 0.3 s of CPU per second of audio, the speech benchmark measures
it). A second front end at 120 frames per second and eight Gaussians
recovered a few fast synthetic voices but doubled the time; with the
confirmation question those utterances are asked about instead of lost.
Since the grammar search got its minimal automaton the time would allow
the second front end, but four searches agree less often than two, and it
carried out fewer commands at once (64 of the tuning set's 162 against 76).

Why the grammar pass gives one sentence and the n-gram pass the alternatives:
the n-best list comes from a word lattice, and the lattice of a grammar
search costs several times the search itself (over a second of CPU per
second of speech, tens of seconds for some laughter), while the n-gram
search's lattice is cheap. So the grammar search runs without one
(PocketSphinx's ``bestpath`` off, read when a search is made) and yields
its best sentence; the n-gram search yields its n-best. Either list is read
only when its search reached the end of a sentence: without a complete path
the n-best search wanders the whole lattice and yields nothing usable.
"""

from __future__ import annotations

import itertools
import logging
import math
import tempfile
from collections import Counter
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from pocketsphinx import Decoder

from services.nlu.compound import SPOKEN_JOINS
from services.nlu.nbest import STOP_SHARE
from services.speech.audio import dither
from services.speech.automaton import minimal_grammar
from services.speech.grammar import SceneWords, build_jsgf, in_grammar, sentence_matcher, skill_words
from services.speech.ngram import arpa, sample_sentences
from services.speech.pronounce import guessed
from services.speech.vocabulary import SpeechVocabulary

log = logging.getLogger("hfpbd.speech")

NBEST = 5
FRAME_RATES = (100,)  # frames per second of the front ends whose hypotheses are pooled
TOP_GAUSSIANS = 4  # per frame and codebook scored by the acoustic model (PocketSphinx's topn)
_BASE_RATE = 100  # log-likelihoods are compared per this many frames
PER_MEANING = 3  # phrases per meaning in the grammar: the plain, usual ones (None: every phrase)
NBEST_SEARCH = 20  # lattice paths read to find NBEST distinct sentences
# PocketSphinx scores acoustic frames as if independent, which overstates how
# sure it is; this scale turns score differences into usable probabilities
# (the speech benchmark shows command accuracy for several scales).
ACOUSTIC_SCALE = 0.03
MIN_POSTERIOR = 1e-6
# prior weight of a sentence that is not one of the scene grammar's (heard by the n-gram pass only):
# it may name an absent object or be a mishearing, so it must sound clearly better to win
OFF_GRAMMAR_PRIOR = 0.1
# prior weight of a sentence of two steps ("... and then ..."): two commands in one breath are rarer than one,
# and a short command is easily heard with a step after it ("switch to the next action" as "switch two and
# then execute"); chosen on the held-out set
COMPOUND_PRIOR = 0.1
_SCORE_UNIT = 1024.0  # PocketSphinx reports scores shifted down by 10 bits
# settings PocketSphinx reads when a search is made. The grammar search has no lattice (see the module notes) and
# wider beams than PocketSphinx's defaults: its automaton is minimal (services.speech.automaton), so the words
# that may follow a word share one state, compete in one beam, and the defaults pruned the right sentence
# ("look at the blue cup" heard as "look at blue cup"); searched this wide it still costs under half the old shape's
GRAMMAR_SEARCH: dict[str, float | bool] = {"bestpath": False, "beam": 1e-80, "pbeam": 1e-80, "wbeam": 1e-60}
NGRAM_SEARCH: dict[str, float | bool] = {"bestpath": True}


class RecogniserError(RuntimeError):
    """The recogniser could not be set up (bad grammar, missing model)."""


@dataclass(frozen=True)
class Hypothesis:
    """One sentence the recogniser heard; ``score`` is its probability within the n-best (they sum to 1)."""

    text: str
    score: float
    loglik: float = 0.0  # the recogniser's scaled-down acoustic log-likelihood, for re-weighting
    in_grammar: bool = True  # a sentence of the scene grammar (else heard by the n-gram pass only)
    first: int = 0  # how many of the recogniser's searches ranked this sentence first

    def to_json(self) -> dict[str, object]:
        return {"text": self.text, "score": float(f"{self.score:.6g}"), "first": self.first}


def _decoder(mllr: Path | None) -> Decoder:
    """PocketSphinx with the shipped en-us model, adapted to a speaker by ``mllr`` when given."""
    if mllr is None:
        return Decoder(lm=None, loglevel="FATAL", topn=TOP_GAUSSIANS)
    if not mllr.is_file():
        raise RecogniserError(f"no voice adaptation file at {mllr} (make one with 'hfpbd speech enrol')")
    try:
        return Decoder(lm=None, loglevel="FATAL", topn=TOP_GAUSSIANS, mllr=str(mllr))
    except (RuntimeError, ValueError) as exc:
        raise RecogniserError(f"the voice adaptation file {mllr} could not be used ({exc}); enrol again") from None


class Recogniser:
    """A PocketSphinx decoder whose grammar follows the vocabulary and the scene.

    Not thread-safe: one thread decodes (the service's decoding worker).
    """

    def __init__(
        self,
        vocabulary: SpeechVocabulary,
        scene: SceneWords = SceneWords(),
        per_meaning: int | None = PER_MEANING,
        nbest: int = NBEST,
        acoustic_scale: float = ACOUSTIC_SCALE,
        ngram: bool = True,
        frame_rates: tuple[int, ...] = FRAME_RATES,
        mllr: Path | None = None,
    ) -> None:
        """``mllr``: a speaker's MLLR transform (``hfpbd speech enrol``) applied to the acoustic model's means."""
        self._decoder = _decoder(mllr)
        self._frame_rates = frame_rates
        self._nbest = nbest
        self._scale = acoustic_scale
        self._per_meaning = per_meaning
        self._search: str | None = None
        self._ngram_search: str | None = None
        self._use_ngram = ngram
        self._version = 0
        self.vocabulary = vocabulary
        self.scene = scene
        self.skills: frozenset[str] = frozenset()  # the taught skills' names the grammar takes as verbs
        self._ngram_skills: frozenset[str] | None = None
        self.unpronounceable: set[str] = set()
        self.jsgf = ""
        self.set_vocabulary(vocabulary, scene)

    def set_vocabulary(self, vocabulary: SpeechVocabulary, scene: SceneWords | None = None) -> None:
        """Regenerate the grammar; words missing from the pronunciation dictionary are left out."""
        words = vocabulary.words()
        self.unpronounceable = {w for w in words if not self._pronounceable(w)}
        whole = vocabulary.restricted(words - self.unpronounceable).without_homophones(self._sound)
        usable = whole.core(self._per_meaning) if self._per_meaning else whole
        scene = self.scene if scene is None else scene
        jsgf = build_jsgf(usable, scene, self.skills)
        if jsgf == self.jsgf:
            return
        self._version += 1
        if self._use_ngram and (
            vocabulary is not self.vocabulary or self._ngram_search is None or self._ngram_skills != self.skills
        ):
            self._set_ngram(whole)
        name = f"commands{self._version}"
        try:
            with _search_settings(self._decoder, GRAMMAR_SEARCH):
                self._decoder.add_fsg(name, minimal_grammar(self._decoder, name, jsgf))
        except (ValueError, RuntimeError) as exc:
            raise RecogniserError(f"the generated speech grammar does not parse: {exc}") from None
        self._decoder.activate_search(name)
        if self._search is not None:
            self._decoder.remove_search(self._search)
        self._search, self.jsgf, self.vocabulary, self.scene = name, jsgf, vocabulary, scene
        self._matcher = sentence_matcher(jsgf)

    def _set_ngram(self, vocabulary: SpeechVocabulary) -> None:
        """The n-gram pass's model: sentences of the whole vocabulary, any object words."""
        name = f"ngram{self._version}"
        with tempfile.TemporaryDirectory(prefix="hfpbd-lm-") as folder:
            path = Path(folder) / "commands.arpa"
            path.write_text(arpa(sample_sentences(build_jsgf(vocabulary, skills=self.skills))))
            try:
                with _search_settings(self._decoder, NGRAM_SEARCH):
                    self._decoder.add_lm_file(name, str(path))
            except RuntimeError as exc:
                raise RecogniserError(f"the generated n-gram model does not load: {exc}") from None
        if self._ngram_search is not None:
            self._decoder.remove_search(self._ngram_search)
        self._ngram_search, self._ngram_skills = name, self.skills

    def _pronounceable(self, word: str) -> bool:
        """Whether the dictionary has ``word``, adding compounds of two known words ("left" + "most")."""
        if self._decoder.lookup_word(word) is not None:
            return True
        for cut in range(2, len(word) - 1):
            head, tail = self._decoder.lookup_word(word[:cut]), self._decoder.lookup_word(word[cut:])
            if head is not None and tail is not None:
                self._decoder.add_word(word, f"{head} {tail}", True)
                return True
        return False

    def _sayable_name(self, word: str) -> bool:
        """Whether a word of a skill's name can be heard: in the dictionary, or pronounced by spelling rules
        (:mod:`services.speech.pronounce`), added to the dictionary then."""
        if self._pronounceable(word):
            return True
        phones = guessed(word)
        if phones is None:
            return False
        self._decoder.add_word(word, phones, True)
        log.info("the skill name's word %r is not in the speech dictionary; pronounced as %s", word, phones)
        return True

    def _sound(self, phrase: str) -> str:
        return " ".join(self._decoder.lookup_word(word) or word for word in phrase.split())

    def set_scene(self, scene: SceneWords) -> None:
        if scene != self.scene:
            self.set_vocabulary(self.vocabulary, scene)

    def set_skills(self, names: Iterable[str]) -> None:
        """Take the taught skills' names as verbs; a name with a word nothing can pronounce is left out (logged).

        The words around a skill ("do it again with", "every") must all be
        pronounceable, or no skill sentence is heard at all.
        """
        if not all(self._pronounceable(word) for word in skill_words()):
            log.warning("the speech dictionary lacks a word of the skill sentences: skills can be typed, not said")
            return
        sayable = set()
        for name in names:
            spoken = " ".join(name.lower().replace("-", " ").split())
            if spoken and all(word.isalpha() and self._sayable_name(word) for word in spoken.split()):
                sayable.add(spoken)
            else:
                log.info("the skill name %r has a word no pronunciation was found for: it can be typed, not said", name)
        if frozenset(sayable) != self.skills:
            self.skills = frozenset(sayable)
            self.set_vocabulary(self.vocabulary, self.scene)

    def decode(self, pcm: np.ndarray, acoustic_scale: float | None = None) -> list[Hypothesis]:
        """Decode one utterance (16 kHz int16); best first, empty when nothing in the grammar was heard.

        The grammar pass's best sentence stays first (it is the sentence of
        the scene's command language); the n-gram pass adds alternatives.
        """
        audio = dither(pcm).tobytes()
        pooled: dict[str, float] = {}
        firsts: list[tuple[bool, float, str]] = []  # each front end's first choice: (in grammar, loglik, text)
        ranked_first: Counter[str] = Counter()  # each search's first choice
        for rate in self._frame_rates:
            grammar, ngram = self._front_end(rate, audio)
            combined = {**ngram, **grammar}  # a sentence both passes heard keeps the grammar's likelihood
            for scored in (grammar, ngram):
                if scored:
                    ranked_first[next(iter(scored))] += 1
            preferred = grammar or ngram
            if preferred:
                text, loglik = next(iter(preferred.items()))
                firsts.append((in_grammar(self._matcher, text), loglik, text))
            for text, loglik in combined.items():
                pooled[text] = max(pooled.get(text, -math.inf), loglik)
        if not firsts:
            return []
        first = max(firsts)[2]
        ordered = {first: pooled.pop(first), **pooled}
        members = {text for text in ordered if in_grammar(self._matcher, text)}
        scale = self._scale if acoustic_scale is None else acoustic_scale
        return [
            replace(h, first=ranked_first[h.text]) for h in posteriors(ordered, scale, members, keep=set(ranked_first))
        ]

    def heard_stop(self, hypotheses: list[Hypothesis]) -> bool:
        """Whether sentences that say nothing but stop hold the share of ``hypotheses`` the NLU acts on a stop at."""
        return sum(h.score for h in hypotheses if self.vocabulary.only_stop(h.text)) >= STOP_SHARE

    def _front_end(self, rate: int, audio: bytes) -> tuple[dict[str, float], dict[str, float]]:
        """Both passes at ``rate`` frames per second, each's sentences best first, log-likelihoods per 100 frames.

        A grammar result that is no sentence of the grammar is the search's
        best partial path (a mishearing) and is left out.
        """
        if self._decoder.config["frate"] != rate:
            self._decoder.config["frate"] = rate
            self._decoder.reinit_feat()
        per_base = _BASE_RATE / rate
        grammar = {
            text: loglik * per_base
            for text, loglik in self._pass(self._search, audio, alternatives=False).items()
            if in_grammar(self._matcher, text)
        }
        ngram = {text: loglik * per_base for text, loglik in self._pass(self._ngram_search, audio).items()}
        return grammar, ngram

    def _pass(self, search: str | None, audio: bytes, alternatives: bool = True) -> dict[str, float]:
        """One search over the audio: its best sentence and, with ``alternatives``, its n-best, with log-likelihoods."""
        if search is None:
            return {}
        self._decoder.activate_search(search)
        self._decoder.start_utt()
        self._decoder.process_raw(audio, no_search=False, full_utt=True)
        self._decoder.end_utt()
        best = self._decoder.hyp()
        if best is None or not best.hypstr:
            return {}
        scored = {best.hypstr: self._loglik(best.score)}
        if not alternatives:
            return scored
        for hyp in itertools.islice(self._decoder.nbest(), NBEST_SEARCH):
            if len(scored) >= self._nbest:
                break
            if hyp is not None and hyp.hypstr and hyp.hypstr not in scored:
                scored[hyp.hypstr] = self._loglik(hyp.score)
        return scored

    def _loglik(self, score: float) -> float:
        if score <= 0.0:
            return -math.inf
        return math.log(score) * _SCORE_UNIT


@contextmanager
def _search_settings(decoder: Decoder, settings: dict[str, float | bool]) -> Iterator[None]:
    """``settings`` in force while a search is made, the decoder's own ones again after it."""
    before = {key: decoder.config[key] for key in settings}
    for key, value in settings.items():
        decoder.config[key] = value
    try:
        yield
    finally:
        for key, value in before.items():
            decoder.config[key] = value


def posteriors(
    logliks: dict[str, float],
    scale: float,
    members: set[str] | None = None,
    off_grammar_prior: float = OFF_GRAMMAR_PRIOR,
    compound_prior: float = COMPOUND_PRIOR,
    keep: set[str] | None = None,
) -> list[Hypothesis]:
    """Probabilities within the list, the decoder's first choice first.

    Softmax of the scaled log-likelihoods, each times its prior: 1 for a
    sentence of the grammar (``members``; all when None), ``off_grammar_prior``
    otherwise, times ``compound_prior`` for a sentence of two steps.
    Alternatives too unlikely to ever win a rescoring (below
    ``MIN_POSTERIOR``) are left out, unless they are in ``keep`` (a search's first choice, which the NLU
    counts to see whether the searches agree).
    """
    if not logliks:
        return []
    members = set(logliks) if members is None else members
    values = np.array([v * scale for v in logliks.values()])
    finite = np.isfinite(values)
    if not finite.any():
        return [Hypothesis(next(iter(logliks)), 1.0, in_grammar=next(iter(logliks)) in members)]
    priors = np.array(
        [
            (1.0 if text in members else off_grammar_prior) * (compound_prior if _two_steps(text) else 1.0)
            for text in logliks
        ]
    )
    weights = np.where(finite, np.exp(values - values[finite].max()), 0.0) * priors
    probabilities = weights / weights.sum()
    hyps = [
        Hypothesis(text, float(p), loglik, text in members) for (text, loglik), p in zip(logliks.items(), probabilities)
    ]
    kept = keep or set()
    rest = sorted((h for h in hyps[1:] if h.score >= MIN_POSTERIOR or h.text in kept), key=lambda h: -h.score)
    return [hyps[0], *rest]


def _two_steps(text: str) -> bool:
    """Whether a heard sentence joins two steps the way they are said aloud ("… and then …")."""
    return any(f" {join} " in f" {text} " for join in SPOKEN_JOINS)
