"""A trigram language model (ARPA text) of command sentences sampled from a grammar.

Why a second model: the grammar search returns one sentence, the grammar's
own best path, so the NLU has nothing to choose between. A decoder pass with
an n-gram model of the same language, built from sentences of the full
vocabulary and without the scene restriction, hears other phrasings and
objects that are not in view; pooling both passes gives the NLU a real
n-best to rescore with P(C|S).

The model is written in ARPA form with absolute discounting and back-off
weights, which PocketSphinx loads directly.
"""

from __future__ import annotations

import math
import random
from collections import Counter, defaultdict
from collections.abc import Iterable

from services.speech.grammar import closing, parse_rules, split_top

SAMPLES = 6000
SEED = 7
DISCOUNT = 0.5
BOS, EOS = "<s>", "</s>"


def sample_sentences(jsgf: str, count: int = SAMPLES, seed: int = SEED) -> list[str]:
    """``count`` sentences of a grammar (as written by :mod:`grammar`), alternatives as likely as their weights.

    An alternative without a ``/weight/`` weighs 1, so the model learns the
    grammar's rarer forms (two steps, questions) as rarely as it weighs them.
    """
    public, rules = parse_rules(jsgf)
    rng = random.Random(seed)
    return [" ".join(_expand(rules, rules[public], rng)) for _ in range(count)]


def _expand(rules: dict[str, list[str]], tokens: list[str], rng: random.Random) -> list[str]:
    """Words of one random path through ``tokens`` (alternatives, optional and grouped parts, rule references)."""
    alternatives = split_top(tokens)
    weights = [float(a[0].strip("/")) if a and a[0].startswith("/") else 1.0 for a in alternatives]
    chosen = rng.choices(alternatives, weights)[0]
    words: list[str] = []
    i = 0
    while i < len(chosen):
        token = chosen[i]
        if token in ("(", "["):
            end = closing(chosen, i)
            if token == "(" or rng.random() < 0.5:
                words += _expand(rules, chosen[i + 1 : end], rng)
            i = end + 1
            continue
        if token.startswith("<"):
            words += _expand(rules, rules[token.strip("<>")], rng)
        elif not token.startswith("/"):
            words.append(token)
        i += 1
    return words


def arpa(sentences: Iterable[str], order: int = 3, discount: float = DISCOUNT) -> str:
    """An ARPA back-off n-gram model of ``sentences`` (absolute discounting)."""
    counts: list[Counter[tuple[str, ...]]] = [Counter() for _ in range(order + 1)]
    for sentence in sentences:
        words = [BOS, *sentence.split(), EOS]
        for n in range(1, order + 1):
            for i in range(len(words) - n + 1):
                gram = tuple(words[i : i + n])
                if n == 1 or gram[0] != EOS:
                    counts[n][gram] += 1
    unigram_total = sum(c for g, c in counts[1].items() if g != (BOS,))
    logprob: dict[tuple[str, ...], float] = {
        g: (-99.0 if g == (BOS,) else math.log10(c / unigram_total)) for g, c in counts[1].items()
    }
    backoff: dict[tuple[str, ...], float] = {}
    for n in range(2, order + 1):
        followers: dict[tuple[str, ...], list[tuple[str, int]]] = defaultdict(list)
        for gram, c in counts[n].items():
            followers[gram[:-1]].append((gram[-1], c))
        for history, seen in followers.items():
            total = sum(c for _, c in seen)
            lower_mass = sum(10 ** _prob(history[1:] + (w,), logprob, backoff) for w, _ in seen)
            for w, c in seen:
                logprob[history + (w,)] = math.log10((c - discount) / total)
            left = discount * len(seen) / total
            backoff[history] = math.log10(left / max(1.0 - lower_mass, 1e-12))
    lines = ["\\data\\"] + [f"ngram {n}={len(counts[n])}" for n in range(1, order + 1)]
    for n in range(1, order + 1):
        lines += ["", f"\\{n}-grams:"]
        for gram in sorted(counts[n]):
            entry = f"{logprob[gram]:.5f}\t{' '.join(gram)}"
            if n < order and gram in backoff:
                entry += f"\t{backoff[gram]:.5f}"
            lines.append(entry)
    return "\n".join([*lines, "", "\\end\\", ""])


def _prob(gram: tuple[str, ...], logprob: dict[tuple[str, ...], float], backoff: dict[tuple[str, ...], float]) -> float:
    """log10 p(last word | the rest) under the lower orders already computed."""
    if gram in logprob:
        return logprob[gram]
    if len(gram) == 1:
        return -99.0
    return backoff.get(gram[:-1], 0.0) + _prob(gram[1:], logprob, backoff)
