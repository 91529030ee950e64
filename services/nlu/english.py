"""The words of English, so that a real word is never silently taken for a typo of a command word.

Why: typo tolerance reads "pik up the gren cup" as meant, but it also read
"the report was cancelled" as "record", "my back was late" as a pick-up of
the plate and "the bus got fine" as a look at the red cup: everyday words
one or two letters away from the lexicon's. A word that is itself English
is still read as the lexicon word it is nearest to, but the command is then
only offered ("I read 'late' as 'plate'. Did you mean …?"), never run. The
list is the recogniser's own pronunciation dictionary (pocketsphinx's
CMUdict, about 126,000 words), read once, on first use.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

import pocketsphinx

DICTIONARY = Path(pocketsphinx.get_model_path()) / "en-us" / "cmudict-en-us.dict"


@cache
def words() -> frozenset[str]:
    """Every word of the dictionary, lower case (alternative pronunciations, ``word(2)``, folded in)."""
    found = set()
    with DICTIONARY.open(encoding="utf-8", errors="replace") as lines:
        for line in lines:
            word = line.split(" ", 1)[0].split("(", 1)[0].lower()
            if word:
                found.add(word)
    return frozenset(found)


def is_word(token: str) -> bool:
    return token in words()
