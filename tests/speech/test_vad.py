"""Utterances found in a stream, offered to the decoder before their end is sure, and decoded ahead once."""

from __future__ import annotations

import queue

import numpy as np
import pytest

from services.speech import espeak
from services.speech.audio import silence
from services.speech.bench_latency import speech_end
from services.speech.service import Settings, SpeechService
from services.speech.vad import TAIL_FRAMES, WINDOW_FRAMES, UtteranceSplitter
from services.speech.vocabulary import nlu_vocabulary
from tests.waiting import eventually

pytestmark = pytest.mark.skipif(not espeak.available(), reason="espeak-ng is not installed")

FRAME = 480  # 30 ms at 16 kHz, the voice activity detector's frame


def fed_frame_by_frame(splitter: UtteranceSplitter, pcm: np.ndarray) -> tuple[list, list[np.ndarray]]:
    """Each frame's offer (None or a copy) and the utterances that ended."""
    offers, ended = [], []
    for start in range(0, len(pcm), FRAME):
        ended += splitter.feed(pcm[start : start + FRAME])
        offers.append(splitter.candidate)
    return offers, ended


def test_the_utterance_is_offered_before_its_end_is_sure_and_is_exactly_what_ends():
    said = espeak.synthesise("put it on the green box", "en-us", 150)
    offers, ended = fed_frame_by_frame(UtteranceSplitter(), np.concatenate([silence(0.5), said, silence(1.0)]))
    assert len(ended) == 1
    first_offer = next(i for i, offer in enumerate(offers) if offer is not None and len(offer) == len(ended[0]))
    end = next(i for i, offer in enumerate(offers) if offer is None and i > first_offer)
    assert np.array_equal(offers[first_offer], ended[0])
    assert end - first_offer == WINDOW_FRAMES - TAIL_FRAMES  # offered 0.27 s before the end is known


def test_an_offer_is_withdrawn_when_speech_goes_on_after_a_pause():
    first = audible(espeak.synthesise("move your right hand", "en-us", 150))
    second = audible(espeak.synthesise("above the blue cup", "en-us", 150))
    pause = silence(0.3)  # with the voice's own fading, a breath within the sentence: no end of it
    stream = np.concatenate([silence(0.5), first, pause, second, silence(1.0)])
    offers, ended = fed_frame_by_frame(UtteranceSplitter(), stream)
    assert len(ended) == 1, "one sentence, one utterance"
    assert len(ended[0]) > len(first) + len(second)
    lengths = [None if offer is None else len(offer) for offer in offers]
    early = next(i for i, length in enumerate(lengths) if length is not None)
    assert lengths[early] < len(ended[0]) - len(second) // 2, "the part before the pause was offered"
    assert None in lengths[early : lengths.index(len(ended[0]))], "...and withdrawn when the speech went on"


def test_the_service_decodes_an_utterance_once_before_its_end_is_sure(network):
    service = SpeechService(network.hub, Settings(microphone="off"), speaker=None)
    decodings: list[tuple[int, bool]] = []  # the audio's length, and whether the utterance was still open
    decode = service.recogniser.decode

    def noting_when(pcm, *args):
        decodings.append((len(pcm), service._splitter.in_speech))
        return decode(pcm, *args)

    service.recogniser.decode = noting_when  # the real decoder, and when it was asked
    utterances: queue.Queue = queue.Queue()
    network.hub.subscribe(network.hub.keys.utterance, utterances.put)
    service.start()
    try:
        service.feed(np.concatenate([silence(0.5), espeak.synthesise("pick up the green box", "en-us", 150)]))
        quiet = iter(np.split(silence(1.5), 50))  # 30 ms at a time, as a microphone sends it
        while (offer := service._splitter.candidate) is None:
            service.feed(next(quiet))
        eventually(lambda: (len(offer), True) in decodings, timeout=30, what="the offer decoded")
        for chunk in quiet:
            service.feed(chunk)
        heard = utterances.get(timeout=30)
    finally:
        service.close()
    assert heard["text"] == "pick up the green box"
    assert [d for d in decodings if d[0] == len(offer)] == [(len(offer), True)], "decoded once, ahead of its end"


def audible(pcm: np.ndarray) -> np.ndarray:
    """``pcm`` without the synthesiser's own silence after the last word."""
    return pcm[: speech_end(pcm)]


@pytest.mark.parametrize(
    ("sentence", "stop"),
    [
        ("stop", True),
        ("stop please", True),
        ("robot halt now", True),
        ("stop moving", True),
        ("pick up the red cup", False),
        ("stop the red cup", False),
    ],
)
def test_a_sentence_that_says_only_stop_is_known(sentence, stop):
    assert nlu_vocabulary().only_stop(sentence) is stop


def test_a_stop_goes_out_before_the_end_of_its_utterance_is_sure_and_once(network):
    service = SpeechService(network.hub, Settings(microphone="off"), speaker=None)
    utterances: queue.Queue = queue.Queue()
    network.hub.subscribe(network.hub.keys.utterance, utterances.put)
    service.start()
    try:
        service.feed(np.concatenate([silence(0.5), espeak.synthesise("stop", "en-us", 150)]))
        quiet = iter(np.split(silence(1.5), 50))
        while service._splitter.candidate is None:
            service.feed(next(quiet))
        heard = utterances.get(timeout=30)
        assert service._splitter.in_speech, "sent while the end of the utterance was not yet sure"
        assert service.recogniser.vocabulary.only_stop(heard["text"])
        for chunk in quiet:
            service.feed(chunk)
        service.feed(np.concatenate([espeak.synthesise("open your left hand", "en-us", 150), silence(1.0)]))
        assert utterances.get(timeout=30)["text"] == "open your left hand", "the stop is not sent twice"
    finally:
        service.close()
