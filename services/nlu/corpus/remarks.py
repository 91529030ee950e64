"""Input that is no command, generated: what a robot hears and reads that was never meant for it.

Why generated: the ``not_meant`` cases of the corpus are the ones found by
hand; a seeded generator reaches the shapes nobody thought of. Four kinds,
drawn evenly: numbers alone (digits, decimals, number words, counting),
code and markup (tags, calls, queries, paths, shell), remarks to someone
else ("the meeting was boring yesterday"), and questions about other things
("when does the news start"). None of them may move the robot: a stop is
the one command that may come of them (stopping is always safe), anything
else is a miss. The words come from everyday talk, not from the lexicon,
and the benchmark and the test draw with different seeds.
"""

from __future__ import annotations

import random

from services.nlu.lexicon import NUMBER_WORDS

_SUBJECTS = (
    "I", "we", "you", "my sister", "the kids", "our team", "the weather", "this coffee", "the meeting",
    "that movie", "the train", "my phone", "the printer", "your mother", "the neighbours", "the report",
    "the news", "the bus", "dinner", "the party", "my back", "the game",
)  # fmt: skip
_VERBS = ("was", "seems", "is going to be", "looked", "sounded", "will be", "has been", "felt", "is", "got")
_ADJECTIVES = (
    "great", "late", "boring", "too long", "amazing", "cold", "broken", "expensive", "fine", "weird", "loud",
    "delicious", "early", "cancelled", "busy", "over",
)  # fmt: skip
_TAILS = ("today", "yesterday", "last week", "this morning", "again", "for sure", "I think", "honestly", "as usual", "")
_ASKED = (
    "what time is", "where is", "who took", "did you see", "have you heard about", "when does", "why is", "how was",
    "is there", "who has", "whose turn is",
)  # fmt: skip
_CODE = (
    "<div class='{w}'>{n}</div>", "{w}({n})", "SELECT * FROM {w} WHERE id = {n};", "/usr/local/{w}/{n}",
    "rm -rf /{w}", "{{\"{w}\": {n}}}", "https://{w}.example/{n}", "{w} = {n}", "#include <{w}.h>",
    "$({w} {n})", "[{w}]({n})", "if ({w} > {n}) {{ return; }}",
)  # fmt: skip
_CODE_WORDS = ("main", "robot", "cup", "user", "data", "table", "arm", "value", "pick_up", "config")


def remarks(count: int, seed: int) -> list[str]:
    """``count`` inputs that are no command, a quarter of each kind, the same for the same seed."""
    rng = random.Random(seed)
    makers = (_number, _code, _remark, _question)
    return [makers[i % len(makers)](rng) for i in range(count)]


def _number(rng: random.Random) -> str:
    words = sorted(NUMBER_WORDS)
    return rng.choice(
        (
            str(rng.randint(0, 99999)),
            f"{rng.uniform(-100, 100):.2f}",
            rng.choice(words),
            " ".join(rng.choice(words) for _ in range(rng.randint(3, 5))),
            " ".join(str(rng.randint(0, 9)) for _ in range(rng.randint(3, 6))),
        )
    )


def _code(rng: random.Random) -> str:
    return rng.choice(_CODE).format(w=rng.choice(_CODE_WORDS), n=rng.randint(0, 99))


def _remark(rng: random.Random) -> str:
    return f"{rng.choice(_SUBJECTS)} {rng.choice(_VERBS)} {rng.choice(_ADJECTIVES)} {rng.choice(_TAILS)}".strip()


def _question(rng: random.Random) -> str:
    return f"{rng.choice(_ASKED)} {rng.choice(_SUBJECTS[8:])}"
