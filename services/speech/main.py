"""``hfpbd speech``: the speech service; ``hfpbd speech decode FILE.wav...`` to try the recogniser;
``hfpbd speech enrol`` to adapt it to a person's voice."""

from __future__ import annotations

import argparse
import json
import sys
import threading
from collections.abc import Sequence
from pathlib import Path

from services.speech import enrol
from services.speech.adapt import AdaptationError, check_matrix
from services.speech.audio import AudioError, read_wav
from services.speech.gate import judge
from services.speech.recogniser import PER_MEANING, Recogniser, RecogniserError
from services.speech.service import Settings, SpeechService
from services.speech.vad import UtteranceSplitter
from services.speech.vocabulary import nlu_vocabulary
from services.speech.voice import Speaker
from shared.bus import Bus
from shared.service import run_service, wait_until_stopped

DESCRIPTION = "Spoken commands in (microphone, WAV files, speech/audio stream), spoken feedback out (espeak-ng)."


def _speaker(name: str) -> Path:
    """An enrolled voice's transform, checked while the arguments are read so a bad one is a usage error."""
    try:
        path = enrol.matrix_path(name)
    except enrol.EnrolmentError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return _mllr(str(path))


def _mllr(value: str) -> Path:
    path = Path(value).expanduser()
    if not path.is_file():
        raise argparse.ArgumentTypeError(f"no such file: {path}")
    try:
        check_matrix(path)
    except AdaptationError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return path


def add_adaptation_arguments(parser: argparse.ArgumentParser) -> None:
    """--speaker and --mllr: decode with an enrolled person's voice adaptation."""
    adapted = parser.add_mutually_exclusive_group()
    adapted.add_argument(
        "--speaker",
        dest="mllr",
        type=_speaker,
        default=None,
        metavar="NAME",
        help="decode with the voice enrolled under NAME ('hfpbd speech enrol --name NAME')",
    )
    adapted.add_argument("--mllr", type=_mllr, default=None, metavar="FILE", help="decode with this MLLR transform")


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
    add_adaptation_arguments(parser)


def body(bus: Bus, args: argparse.Namespace, stop: threading.Event) -> None:
    settings = Settings(
        trigger=args.trigger,
        microphone=args.microphone,
        device=args.device,
        per_meaning=None if args.vocabulary == "full" else PER_MEANING,
        wav_files=tuple(args.wav),
        mllr=args.mllr,
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
    add_adaptation_arguments(parser)
    args = parser.parse_args(argv)
    try:
        recogniser = Recogniser(
            nlu_vocabulary(), per_meaning=None if args.vocabulary == "full" else PER_MEANING, mllr=args.mllr
        )
    except RecogniserError as exc:
        print(f"hfpbd speech decode: {exc}", file=sys.stderr)
        return 1
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
    if args and args[0] == "enrol":
        return enrol.main(args[1:])
    return run_service("speech", DESCRIPTION, body, args, add_arguments)
