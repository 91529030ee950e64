"""Textual messages that carry what arrives on the bus into the app.

The bus calls its handlers on worker threads; those handlers only post one of
these messages (``App.post_message`` is thread-safe and never blocks), so all
widget updates happen on Textual's own event loop.
"""

from __future__ import annotations

from PIL import Image
from textual.message import Message

from shared.messages import Cloud, Gripper, NluResult, PerceivedObject, Pose, Robot
from tui.camera import Picture


class BusConnected(Message):
    """The Zenoh session is open and every subscription is declared."""


class BusUnavailable(Message):
    """The Zenoh session could not be opened (e.g. no router reachable in client mode)."""

    def __init__(self, reason: str) -> None:
        super().__init__()
        self.reason = reason


class Said(Message):
    """A line the robot says on ``dialog/say``; ``topic`` is set when it answers a question."""

    def __init__(self, text: str, kind: str, candidates: list[str], topic: str | None = None) -> None:
        super().__init__()
        self.text = text
        self.kind = kind
        self.candidates = candidates
        self.topic = topic


class Understood(Message):
    """An ``nlu/result``: a command or a clarification, with the utterance it answers."""

    def __init__(self, result: NluResult) -> None:
        super().__init__()
        self.result = result


class ObjectsSeen(Message):
    """A ``perception/objects`` sample: every perceived object."""

    def __init__(self, objects: list[PerceivedObject], status: str | None) -> None:
        super().__init__()
        self.objects = objects
        self.status = status


class ExecutorChanged(Message):
    """An ``executor/state`` sample: robot fields, actions, progress, reach."""

    def __init__(self, robot: Robot, reach: dict[str, dict[str, dict[str, bool]]]) -> None:
        super().__init__()
        self.robot = robot
        self.reach = reach


class SimMoved(Message):
    """The latest ``sim/state``: tool poses and gripper readings."""

    def __init__(self, ee: dict[str, Pose], grippers: dict[str, Gripper], moving: dict[str, bool]) -> None:
        super().__init__()
        self.ee = ee
        self.grippers = grippers
        self.moving = moving


class Presence(Message):
    """A service's liveliness token appeared or vanished."""

    def __init__(self, service: str, alive: bool) -> None:
        super().__init__()
        self.service = service
        self.alive = alive


class Latency(Message):
    """Round-trip time of a cheap request to a service, or None when it did not answer."""

    def __init__(self, service: str, seconds: float | None) -> None:
        super().__init__()
        self.service = service
        self.seconds = seconds


class Described(Message):
    """Referring expressions per object id from ``nlu/describe``."""

    def __init__(self, descriptions: dict[str, str]) -> None:
        super().__init__()
        self.descriptions = descriptions


class VocabularyLoaded(Message):
    """Words and phrases the NLU knows, for completion in the input line."""

    def __init__(self, words: list[str], phrases: list[str]) -> None:
        super().__init__()
        self.words = words
        self.phrases = phrases


class RequestFailed(Message):
    """A request the user caused (a key, a choice) failed; the reason is shown in the dialog."""

    def __init__(self, what: str, reason: str) -> None:
        super().__init__()
        self.what = what
        self.reason = reason


class Heard(Message):
    """The speech service heard a command: what it made of the sound and how sure it was (None: not said)."""

    def __init__(self, text: str, sure: float | None) -> None:
        super().__init__()
        self.text = text
        self.sure = sure


class Talking(Message):
    """The speech service answered a push-to-talk press or release: whether it now listens."""

    def __init__(self, listening: bool) -> None:
        super().__init__()
        self.listening = listening


class CloudSeen(Message):
    """A ``sim/cloud`` frame (colour image, organised points, camera pose) for the camera view."""

    def __init__(self, cloud: Cloud) -> None:
        super().__init__()
        self.cloud = cloud


class CameraPictured(Message):
    """A camera frame composed off the UI thread, ready to show."""

    def __init__(self, picture: Picture) -> None:
        super().__init__()
        self.picture = picture


class CameraFailed(Message):
    """A camera frame could not be composed; ``reason`` says why (the view says it instead of a picture)."""

    def __init__(self, reason: str) -> None:
        super().__init__()
        self.reason = reason


class OverviewTaken(Message):
    """The simulator's overview picture of the whole robot, decoded."""

    def __init__(self, image: Image.Image) -> None:
        super().__init__()
        self.image = image
