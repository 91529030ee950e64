"""``hfpbd speech``: the speech service, and ``hfpbd speech decode FILE.wav...`` to try the recogniser."""

from __future__ import annotations

import argparse
import json
import sys
import threading
from collections.abc import Sequence
from pathlib import Path

from services.speech.audio import AudioError, read_wav
from services.speech.gate import judge
from services.speech.recogniser import PER_MEANING, Recogniser
from services.speech.service import Settings, SpeechService
from services.speech.vad import UtteranceSplitter
from services.speech.vocabulary import nlu_vocabulary
from services.speech.voice import Speaker
from shared.bus import Bus
from shared.service import run_service, wait_until_stopped

DESCRIPTION = "Spoken commands in (microphone, WAV files, speech/audio stream), spoken feedback out (espeak-ng)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--trigger",
        choices=("vad", "ptt"),
        default="vad",
        help="vad: every utterance heard is decoded; ptt: only audio while push-to-talk is held",
    )
    parser.add_argument(
        "--microphone",
        choices=("auto", "on", "off"),
        default="auto",
        help="auto: use one if present, else say so once (default); on: fail without one",
    )
    parser.add_argument("--device", default=None, help="input device name or number (default: the system's)")
    parser.add_argument(
        "--wav",
        type=Path,
        action="append",
        default=[],
        metavar="FILE",
        help="decode this WAV file as if it were spoken now (repeatable)",
    )
    parser.add_argument(
        "--vocabulary",
        choices=("core", "full"),
        default="core",
        help="core: the three usual phrases per meaning (more accurate, faster); full: every NLU phrase",
    )
    parser.add_argument("--no-voice", action="store_true", help="do not speak the robot's words")
    parser.add_argument("--voice", default="en-us", help="espeak-ng voice (default en-us)")
    parser.add_argument("--voice-speed", type=int, default=160, help="words per minute (default 160)")
    parser.add_argument(
        "--voice-dir",
        type=Path,
        default=None,
        help="write each spoken sentence as a WAV file here instead of playing it",
    )


def body(bus: Bus, args: argparse.Namespace, stop: threading.Event) -> None:
    settings = Settings(
        trigger=args.trigger,
        microphone=args.microphone,
        device=args.device,
        per_meaning=None if args.vocabulary == "full" else PER_MEANING,
        wav_files=tuple(args.wav),
    )
    speaker = None
    if not args.no_voice:
        if args.voice_dir is not None:
            args.voice_dir.mkdir(parents=True, exist_ok=True)
        speaker = Speaker(args.voice, args.voice_speed, args.voice_dir)
    service = SpeechService(bus, settings, speaker)
    try:
        service.start()
        bus.declare_alive("speech")
        service.play_files()
        wait_until_stopped(stop)
    finally:
        service.close()


def decode_files(argv: Sequence[str]) -> int:
    """Print one JSON line per utterance heard in each file: its n-best list, or why it is no speech."""
    parser = argparse.ArgumentParser(
        prog="hfpbd speech decode", description="Decode WAV files with the command grammar."
    )
    parser.add_argument("files", nargs="+", type=Path)
    parser.add_argument("--vocabulary", choices=("core", "full"), default="core")
    args = parser.parse_args(argv)
    recogniser = Recogniser(nlu_vocabulary(), per_meaning=None if args.vocabulary == "full" else PER_MEANING)
    status = 0
    for path in args.files:
        try:
            pcm = read_wav(path)
        except AudioError as exc:
            print(f"hfpbd speech decode: {exc}", file=sys.stderr)
            status = 1
            continue
        splitter = UtteranceSplitter()
        for utterance in splitter.feed(pcm) + splitter.flush():
            verdict = judge(utterance)
            hypotheses = recogniser.decode(utterance) if verdict.speech else []
            heard: dict[str, object] = {
                "file": str(path),
                "text": hypotheses[0].text if hypotheses else None,
                "nbest": [h.to_json() for h in hypotheses],
            }
            if not verdict.speech:
                heard["not_speech"] = verdict.reason
            print(json.dumps(heard))
    return status


def main(argv: list[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    if args and args[0] == "decode":
        return decode_files(args[1:])
    return run_service("speech", DESCRIPTION, body, args, add_arguments)
