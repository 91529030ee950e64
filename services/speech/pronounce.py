"""Pronunciations for skill names the speech dictionary lacks, from espeak-ng's letter-to-sound rules.

Why: a person names a skill with any word ("declutter", "plonk"), and a name
the dictionary lacks could be typed but not said, so that skill was out of
reach of someone who cannot type. espeak-ng, already the robot's voice,
knows how English spelling sounds; its phonemes (``-x --sep=_``, US English)
are mapped here onto the acoustic model's phone set (the CMU dictionary's).

Only skill names go through this: the command vocabulary's words are all in
the dictionary, and a guessed pronunciation is a guess. A word with a phoneme
this table does not know is left unpronounceable rather than guessed worse.
"""

from __future__ import annotations

from services.speech import espeak

# espeak-ng's US English phoneme mnemonics -> CMU dictionary phones (a vowel with its r-colouring as two)
PHONES: dict[str, tuple[str, ...]] = {
    **{c: (p,) for c, p in zip("pbtdkgfvszhmnlrwj", "P B T D K G F V S Z HH M N L R W Y".split(), strict=True)},
    "t#": ("T",),  # the flap in "water"
    "t2": ("T",),
    "?": ("T",),  # a glottal stop, where US English has a t ("button")
    "x": ("K",),  # the Scottish "loch": the nearest English phone
    "T": ("TH",),
    "D": ("DH",),
    "S": ("SH",),
    "Z": ("ZH",),
    "N": ("NG",),
    "tS": ("CH",),
    "dZ": ("JH",),
    "n-": ("N",),
    "l-": ("L",),
    "m-": ("M",),
    "r-": ("R",),
    "I": ("IH",),
    "I#": ("IH",),
    "I2": ("IH",),
    "i": ("IY",),
    "i:": ("IY",),
    "E": ("EH",),
    "a": ("AE",),
    "a#": ("AH",),
    "aa": ("AE",),
    "A:": ("AA",),
    "0": ("AA",),
    "O": ("AO",),
    "O:": ("AO",),
    "O2": ("AA",),
    "V": ("AH",),
    "U": ("UH",),
    "u:": ("UW",),
    "3": ("ER",),
    "3:": ("ER",),
    "@": ("AH",),
    "@2": ("AH",),
    "@5": ("AH",),
    "@-": ("AH",),
    "@L": ("AH", "L"),
    "aI": ("AY",),
    "aU": ("AW",),
    "OI": ("OY",),
    "eI": ("EY",),
    "oU": ("OW",),
    "A@": ("AA", "R"),
    "o@": ("AO", "R"),
    "O@": ("AO", "R"),
    "e@": ("EH", "R"),
    "i@": ("IH", "R"),
    "i@3": ("IH", "R"),
    "U@": ("UH", "R"),
    "aI3": ("AY", "ER"),
    "aI@": ("AY", "ER"),
    "aU@": ("AW", "ER"),
}
STRESS = "',;%="  # espeak-ng's stress and syllable marks: no phones


def espeak_phonemes(word: str) -> list[str]:
    """espeak-ng's phonemes for ``word`` (US English), one mnemonic each; empty when espeak-ng is missing or fails."""
    try:
        out = espeak.phonemes(word)
    except espeak.EspeakError:
        return []
    marks = str.maketrans("", "", STRESS)
    return [p for p in (token.translate(marks) for token in out.strip().split("_")) if p]


def guessed(word: str) -> str | None:
    """CMU phones for a single alphabetic ``word`` by espeak-ng's rules ("P L AA NG K"), or None when it cannot say."""
    if not word.isalpha():
        return None
    espeak = espeak_phonemes(word.lower())
    if not espeak or any(p not in PHONES for p in espeak):
        return None
    return " ".join(phone for p in espeak for phone in PHONES[p])
