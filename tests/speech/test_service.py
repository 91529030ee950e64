"""The speech service as a real process: audio on the bus in, NLU commands out, voice out."""

from __future__ import annotations

import queue
import time
from pathlib import Path

import numpy as np
import pytest

from services.speech import espeak, sounds
from services.speech.audio import RATE, AudioError, read_wav, silence
from shared.bus import RemoteError
from shared.keys import Keys
from tests.speech.helpers import stream
from tests.waiting import eventually, subscribed

pytestmark = pytest.mark.skipif(not espeak.available(), reason="espeak-ng is not installed")

OBJECTS = [
    {"id": "obj0", "color": "red", "type": "cup", "position": [0.55, -0.15, 0.77], "size": [0.07, 0.07, 0.1]},
    {"id": "obj1", "color": "blue", "type": "cup", "position": [0.6, 0.15, 0.77], "size": [0.07, 0.07, 0.1]},
    {"id": "obj2", "color": "green", "type": "box", "position": [0.5, 0.0, 0.76], "size": [0.08, 0.08, 0.08]},
]


def collect(bus, key: str, **options) -> queue.Queue:
    inbox: queue.Queue = queue.Queue()
    bus.subscribe(key, inbox.put, **options)
    return inbox


@pytest.mark.parametrize("tail_s", [1.0, 0.0], ids=["silence-after", "stream-stops-mid-utterance"])
def test_spoken_command_reaches_the_nlu_as_a_command(network, launcher, tail_s: float):
    hub = network.hub
    hub.publisher(hub.keys.objects, cached=True).put({"stamp": time.time(), "objects": OBJECTS})
    utterances = collect(hub, hub.keys.utterance)
    results = collect(hub, hub.keys.nlu_result)
    status = collect(hub, hub.keys.speech("status"), history=True)
    launcher.start("nlu")
    launcher.start("speech", "--microphone", "off", "--no-voice")
    status.get(timeout=30)  # published after its audio subscription: audio sent now is not lost in routing
    said = espeak.synthesise("pick up the green box with your right hand", "en-us", 140)
    stream(hub, np.concatenate([silence(0.5), said, silence(tail_s)]))  # no "end": the stream just stops

    utterance = utterances.get(timeout=60)
    assert utterance["source"] == "speech"
    assert utterance["text"] == "pick up the green box with your right hand"
    assert utterance["nbest"][0]["text"] == utterance["text"] and utterance["nbest"][0]["score"] > 0
    result = results.get(timeout=30)
    meant = {"procedure": "pick_up", "args": {"arm": "right", "object": "obj2"}}
    if result["kind"] == "clarify":  # the recogniser's searches disagreed: asked about, not acted on
        assert result["question"].startswith("Did you say") and result["candidates"] == [meant]
    else:
        assert result["kind"] == "command" and {"procedure": result["procedure"], "args": result["args"]} == meant


def test_non_speech_is_dropped_before_the_next_command(network, launcher):
    hub = network.hub
    hub.publisher(hub.keys.objects, cached=True).put({"stamp": time.time(), "objects": OBJECTS})
    utterances = collect(hub, hub.keys.utterance)
    status = collect(hub, hub.keys.speech("status"), history=True)
    launcher.start("speech", "--microphone", "off", "--no-voice")
    status.get(timeout=30)
    noise = [sounds.sound(kind, 5, 1.5) for kind in ("white noise", "hum", "coughs", "chords")]
    command = espeak.synthesise("look at the red cup", "en-gb", 150)
    started = time.monotonic()
    stream(
        hub, np.concatenate([silence(0.5), *(np.concatenate([n, silence(0.8)]) for n in noise), command, silence(1.0)])
    )
    # the first utterance published is the command: no sound before it became one
    assert utterances.get(timeout=60)["text"] == "look at the red cup"
    assert time.monotonic() - started < 30


def test_a_taught_skill_said_by_name_reaches_the_nlu_as_that_skill_run(network, launcher):
    hub = network.hub
    hub.publisher(hub.keys.objects, cached=True).put({"stamp": time.time(), "objects": OBJECTS})
    # the executor's state as it is once action 1 is called "stack" (the NLU and the speech service read it)
    state = {
        "stamp": time.time(),
        "robot": {"grippers": {"right": "open", "left": "open"}, "action": 1, "actions": [2]},
        "reach": {},
        "skills": [{"name": "stack", "action": 1}],
    }
    hub.publisher(hub.keys.executor_state, cached=True).put(state)
    results = collect(hub, hub.keys.nlu_result)
    status = collect(hub, hub.keys.speech("status"), history=True)
    launcher.start("nlu")
    launcher.start("speech", "--microphone", "off", "--no-voice")
    # each status is read as it comes (a blocking get): the one after the grammar took the name says so
    eventually(lambda: status.get(timeout=60)["skills"] == ["stack"], 60, "the speech grammar to take the skill")
    subscribed(hub, hub.keys.utterance)
    said = espeak.synthesise("stack the red cup on the green box", "en-us", 150)
    stream(hub, np.concatenate([silence(0.5), said, silence(1.0)]))
    result = results.get(timeout=60)
    meant = {"procedure": "run_skill", "args": {"skill": "stack", "objects": {"carried": "obj0", "landmark": "obj2"}}}
    if result["kind"] == "clarify":  # the recogniser's searches disagreed: asked about, not acted on
        assert result["question"].startswith("Did you say") and result["candidates"] == [meant]
    else:
        assert result["kind"] == "command" and {"procedure": result["procedure"], "args": result["args"]} == meant


def test_a_command_heard_unsure_is_asked_about_and_yes_runs_it(network, launcher):
    hub = network.hub
    hub.publisher(hub.keys.objects, cached=True).put({"stamp": time.time(), "objects": OBJECTS})
    results = collect(hub, hub.keys.nlu_result)
    launcher.start("nlu")
    subscribed(hub, hub.keys.utterance)  # the NLU's subscription is routed: the utterance is not lost
    # the two searches ranked different commands first: asked about
    hub.publish(
        hub.keys.utterance,
        {
            "text": "point at the red cup",
            "source": "speech",
            "nbest": [
                {"text": "point at the red cup", "score": 0.8, "first": 1},
                {"text": "point at the blue cup", "score": 0.2, "first": 1},
            ],
        },
    )
    question = results.get(timeout=30)
    assert question["kind"] == "clarify" and question["question"] == "Did you say: point at the red cup?"
    assert question["candidates"] == [{"procedure": "point_to", "args": {"arm": "right", "object": "obj0"}}]
    hub.publish(
        hub.keys.utterance, {"text": "yes", "source": "speech", "nbest": [{"text": "yes", "score": 1.0, "first": 2}]}
    )
    done = results.get(timeout=30)
    assert done["kind"] == "command" and done["procedure"] == "point_to" and done["args"]["object"] == "obj0"


def test_missing_microphone_is_reported_once_and_push_to_talk_still_works(network, launcher):
    hub = network.hub
    says = collect(hub, hub.keys.say)
    utterances = collect(hub, hub.keys.utterance)
    proc = launcher.start("speech", "--trigger", "ptt", "--device", "no-such-device", "--no-voice")
    report = says.get(timeout=10)
    assert report["kind"] == "info" and report["text"].startswith("No microphone:")
    assert "typing works" in report["text"]
    status = collect(hub, Keys(network.namespace).speech("status"), history=True).get(timeout=10)
    assert status["microphone"] is False and status["microphone_problem"]
    assert "Traceback" not in proc.log()

    said = np.concatenate([silence(0.3), espeak.synthesise("look at the red cup", "en-gb", 150), silence(0.3)])
    stream(hub, said)  # push-to-talk not held: ignored
    with pytest.raises(queue.Empty):
        utterances.get(timeout=3)
    ptt = Keys(network.namespace).speech("ptt")
    assert hub.request(ptt, {"on": True})["listening"] is True
    stream(hub, said)
    assert hub.request(ptt, {"on": False})["listening"] is False
    assert utterances.get(timeout=60)["text"] == "look at the red cup"
    with pytest.raises(RemoteError, match="on"):
        hub.request(ptt, {"on": "yes"})
    with pytest.raises(queue.Empty):
        says.get(timeout=1)  # the missing microphone was not reported a second time


def test_robot_words_are_spoken(network, launcher, tmp_path: Path):
    folder = tmp_path / "voice"
    launcher.start("speech", "--microphone", "off", "--voice-dir", str(folder))
    network.hub.publish(network.hub.keys.say, {"text": "I picked up the green box.", "kind": "narration"})

    def spoken_seconds() -> float:
        """How long the sentence written so far lasts (0 while espeak-ng has not written a readable file)."""
        try:
            return sum(len(read_wav(path)) / RATE for path in folder.glob("say-*.wav"))
        except AudioError:
            return 0.0

    eventually(lambda: spoken_seconds() > 0.8, 20, "the sentence spoken into a WAV file")
    assert len(list(folder.glob("say-*.wav"))) == 1


def test_wav_files_wait_for_the_nlu_grammar_before_decoding(network, launcher, tmp_path: Path):
    hub = network.hub
    heard: queue.Queue = queue.Queue()  # status and utterances in the order they arrive
    hub.subscribe(hub.keys.speech("status"), lambda m: heard.put(("status", m)))
    hub.subscribe(hub.keys.utterance, lambda m: heard.put(("utterance", m)))
    path = tmp_path / "said.wav"
    espeak.write("look at the red cup", path, "en-us", 150)
    launcher.start("speech", "--microphone", "off", "--no-voice", "--wav", str(path))
    launcher.start("nlu")  # only now: a file decoded without waiting would have been heard already
    grammars = []
    while (message := heard.get(timeout=90))[0] == "status":
        grammars.append(message[1]["grammar"])
    assert grammars and grammars[-1] == "nlu", grammars
    assert message[1]["text"] == "look at the red cup"
