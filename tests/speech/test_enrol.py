"""Voice enrolment end to end: espeak-ng reads the prompts, SphinxTrain adapts, the recogniser uses the result."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from services.speech import espeak
from services.speech.adapt import AdaptationError, check_matrix, find_tools
from services.speech.audio import silence, write_wav
from services.speech.corpus import corpus
from services.speech.enrol import MATRIX_FILE, RECORDINGS, EnrolmentError, matrix_path
from services.speech.main import decode_files, main
from services.speech.prompts import PROMPTS, prompt_file
from services.speech.recogniser import Recogniser
from services.speech.sphinx_model import default_model_dir, read_binary_mdef, read_sendump
from services.speech.vocabulary import nlu_vocabulary


def _tools_installed() -> bool:
    try:
        find_tools()
    except AdaptationError:
        return False
    return True


pytestmark = [
    pytest.mark.skipif(not espeak.available(), reason="espeak-ng is not installed"),
    pytest.mark.skipif(not _tools_installed(), reason="sphinxtrain / sphinxbase-utils are not installed"),
]

VOICE, SPEED = "en-us+m3", 170
HELD_OUT = "move your right hand up"  # a corpus sentence that is no prompt


@pytest.fixture(scope="module")
def readings(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The prompts read by one espeak-ng voice, as the files ``hfpbd speech enrol --wav-dir`` reads."""
    folder = tmp_path_factory.mktemp("readings")
    for number, text in enumerate(PROMPTS, 1):
        espeak.write(text, folder / prompt_file(number), VOICE, SPEED)
    return folder


@pytest.fixture(scope="module")
def data_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("data")


@pytest.fixture(scope="module")
def enrolled(readings: Path, data_dir: Path) -> Path:
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("HFPBD_DATA_DIR", str(data_dir))
        assert main(["enrol", "--name", "tester", "--wav-dir", str(readings)]) == 0
        return matrix_path("tester")


def test_prompts_are_not_the_sentences_adaptation_is_measured_on() -> None:
    assert len(set(PROMPTS)) == len(PROMPTS) >= 15
    assert not set(PROMPTS) & {item.text for item in corpus()}
    assert HELD_OUT in {item.text for item in corpus()}
    words = nlu_vocabulary().words()
    assert {w for p in PROMPTS for w in p.split()} <= words


def test_the_shipped_model_converts_for_sphinxtrain() -> None:
    definition = read_binary_mdef(default_model_dir() / "mdef")
    assert definition.n_base == 42 and len(definition.phones) > 100_000
    assert {p.base for p in definition.phones if p.filler} >= {"SIL"}
    weights = read_sendump(default_model_dir() / "sendump")
    assert weights.shape == (definition.n_senones, 3, 128)
    assert np.allclose(weights.sum(axis=2), 1.0, atol=1e-5)


def test_enrolment_writes_a_transform_and_keeps_the_recordings(enrolled: Path, data_dir: Path) -> None:
    assert enrolled == data_dir / "voices" / "tester" / MATRIX_FILE
    check_matrix(enrolled)
    assert len(list((enrolled.parent / RECORDINGS).glob("prompt_*.wav"))) == len(PROMPTS)


def test_the_adapted_recogniser_decodes_a_sentence_that_was_not_read(enrolled: Path) -> None:
    recogniser = Recogniser(nlu_vocabulary(), mllr=enrolled)
    pcm = np.concatenate([silence(0.3), espeak.synthesise(HELD_OUT, VOICE, SPEED), silence(0.3)])
    assert recogniser.decode(pcm)[0].text == HELD_OUT


def test_decode_takes_the_enrolled_voice_by_name(
    enrolled: Path, data_dir: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("HFPBD_DATA_DIR", str(data_dir))
    wav = tmp_path / "held_out.wav"
    espeak.write(HELD_OUT, wav, VOICE, SPEED)
    assert decode_files(["--speaker", "tester", str(wav)]) == 0
    assert f'"text": "{HELD_OUT}"' in capsys.readouterr().out
    with pytest.raises(SystemExit):
        decode_files(["--speaker", "nobody", str(wav)])
    assert "no enrolled voice 'nobody'" in capsys.readouterr().err


def test_silent_recordings_are_refused_with_a_reason(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("HFPBD_DATA_DIR", str(tmp_path / "data"))
    for number in range(1, len(PROMPTS) + 1):
        write_wav(tmp_path / prompt_file(number), silence(2.0))
    assert main(["enrol", "--name", "quiet", "--wav-dir", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert "prompt_01.wav: no speech in it" in err
    assert "only 0 of the 20 sentences could be used" in err
    assert "Traceback" not in err
    with pytest.raises(EnrolmentError):
        matrix_path("quiet")


def test_a_folder_without_recordings_says_which_files_it_wants(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["enrol", "--wav-dir", str(tmp_path), "--voices-dir", str(tmp_path / "voices")]) == 1
    assert "has none of the recordings prompt_01.wav" in capsys.readouterr().err


def test_a_broken_transform_is_a_usage_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "mllr_matrix"
    bad.write_text("1\n3\n13\n0.5 nan\n")
    with pytest.raises(SystemExit):
        decode_files(["--mllr", str(bad), str(tmp_path / "any.wav")])
    assert "is not a usable MLLR transform" in capsys.readouterr().err


def test_missing_tools_are_named_with_their_packages(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr("services.speech.adapt.TOOL_DIRS", ())
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(AdaptationError, match=r"bw \(Debian package sphinxtrain\)"):
        find_tools()
