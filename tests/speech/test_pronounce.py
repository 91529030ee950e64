"""Skill names the speech dictionary lacks, pronounced by espeak-ng's spelling rules and heard as verbs."""

from __future__ import annotations

from pathlib import Path

import pocketsphinx
import pytest

from services.speech import espeak
from services.speech.grammar import SceneWords, grammar_words
from services.speech.pronounce import guessed
from services.speech.recogniser import Recogniser
from services.speech.vocabulary import nlu_vocabulary

pytestmark = pytest.mark.skipif(not espeak.available(), reason="espeak-ng is not installed")

COMMON = ("water", "church", "measure", "thing", "house", "fire", "bottle", "garden", "judge", "cute", "tour", "oil")


def dictionary() -> dict[str, str]:
    path = Path(pocketsphinx.get_model_path()) / "en-us" / "cmudict-en-us.dict"
    return {word: " ".join(phones) for word, *phones in (line.split() for line in path.read_text().splitlines())}


def test_spelling_rules_give_the_dictionarys_own_phones_for_common_words() -> None:
    known = dictionary()
    assert {word: guessed(word) for word in COMMON} == {word: known[word] for word in COMMON}


def test_a_made_up_word_gets_phones_and_a_word_with_digits_none() -> None:
    assert guessed("declutter") == "D IH K L AH T ER"
    assert guessed("Plonk") == "P L AA NG K"
    assert guessed("r2d2") is None and guessed("") is None


def test_the_recogniser_takes_a_skill_name_the_dictionary_lacks() -> None:
    recogniser = Recogniser(nlu_vocabulary(), SceneWords())
    recogniser.set_skills(["declutter", "zqxwv", "serve", "r2d2"])
    assert recogniser.skills == {"declutter", "zqxwv", "serve"}  # "zqxwv" is spelled out, letter by letter
    assert {"declutter", "zqxwv"} <= grammar_words(recogniser.jsgf)
