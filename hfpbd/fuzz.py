"""``hfpbd bench fuzz``: bad input at volume, against the real services.

Why: every decoder validates and a bad message must be logged and dropped
without touching state (the design notes' contract), however many arrive.
This sends malformed payloads on every stream key the services read and bad
requests to every queryable they serve (the simulator's controls among them), then checks that each service is
still alive (process and liveliness token), still serving (a good request
answered) and unchanged (the same answers as before, no object made up from
junk), and that no log holds a traceback. The tests run it with a smaller count.
"""

from __future__ import annotations

import argparse
import logging
import random
import re
import sys
import tempfile
import time
import uuid
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import msgpack
import msgspec
import zenoh

from hfpbd.spawn import ServiceProcess
from hfpbd.tasks.stack import LocalStack
from shared.bus import Bus
from shared.codec import decode, encode
from shared.config import free_port, loopback_options
from shared.messages import TYPES, ActionList, Objects, Parsed, SimState, Truth, Utterance

# stream key (under pbd/<ns>/) -> the schema its readers hold it to
STREAMS: dict[str, str] = {
    "sim/cloud": "cloud",
    "sim/state": "sim_state",
    "sim/events": "sim_event",
    "perception/objects": "objects",
    "dialog/utterance": "utterance",
    "nlu/result": "nlu_result",
    "executor/state": "executor_state",
    "speech/audio": "speech_audio",
}
# queryable -> well-formed maps the service must refuse (beside payloads that are not messages at all)
REFUSED: dict[str, list[dict[str, Any]]] = {
    "sim/control/arm": [
        {"arm": "third", "positions": [0.0] * 7},
        {"arm": "right", "positions": [0.0] * 3},
        {"arm": "left", "positions": [float("nan")] * 7},
        {"arm": "right", "points": "x", "times": [1.0]},
        {"arm": "right", "points": [[0.0] * 7], "times": [-1.0]},
        {"arm": "left", "joints": ["elbow"], "positions": [0.0] * 7},
        {"arm": "right"},
    ],
    "sim/control/arms": [
        {"arms": {}},
        {"arms": 3},
        {"arms": {"third": {"positions": [0.0] * 7}}},
        {"arms": {"right": 5}},
        {"arms": {"left": {"positions": [0.0] * 3}}},
        {"arms": {"right": {"positions": [float("nan")] * 7}, "left": {"points": "x", "times": [1.0]}}},
        {"arms": {"right": {"points": [[0.0] * 7], "times": [1.0], "contact": "yes"}}},
    ],
    "sim/control/gripper": [
        {"arm": "right", "width": "wide"},
        {"arm": "left", "width": 5.0},
        {"arm": "right", "width": 0.05, "force": -1.0},
        {"arm": None, "width": 0.05},
    ],
    "sim/control/head": [{"look_at": [1.0, 2.0]}, {"pan": "left", "tilt": 0.0}, {"look_at": [float("inf")] * 3}],
    "sim/control/torso": [{"height": 9.0}, {"height": "up"}, {}],
    "sim/control/stop": [{"arm": "third"}, {"arm": 7}],
    "sim/control/scene": [
        {"name": "nowhere"},
        {"name": 5},
        {"name": "default", "seed": "x"},
        {"name": "default", "poses": [1, 2]},
        {"scene": {"objects": 3}},
        {},
    ],
    "sim/control/pause": [{"paused": "yes"}, {"paused": 1}],
    "sim/control/step": [{"steps": -5}, {"steps": "many"}, {"steps": 10**9}, {"steps": 1}],
    "sim/control/snapshot": [],
    "nlu/parse": [{"text": 7}, {"text": "pick it up", "world": "nowhere"}, {"text": "x", "world": {"objects": 3}}],
    "nlu/ground": [{"text": ["a"]}, {"text": "the cup", "world": []}],
    "nlu/describe": [{"world": 5}, {"world": {"objects": [{"id": 1}]}}],
    "nlu/vocabulary": [],
    "speech/ptt": [{"on": "yes"}, {"on": 1}, {"on": None}, {}],
    "perception/record": [],
    "executor/control/command": [
        {"procedure": "teleport", "args": {}},
        {"procedure": 3},
        {"args": []},
        {"procedure": "open", "args": {"arm": "third"}},
    ],
    "executor/control/actions": [
        {"op": "explode"},
        {"op": "delete", "number": 0},
        {"op": "show", "number": "one"},
        {"op": "rename", "number": 1},
        {},
    ],
}
SERVICES = ("sim", "nlu", "perception", "executor", "speech")
# the simulator renders no camera here: perception then sees nothing, so any object it reports came from junk
SIM_ARGS = ("--cloud-rate", "0")
SPEECH_ARGS = ("--microphone", "off", "--no-voice")  # heard only through speech/audio
JOINT_SLACK = 0.01  # rad a joint may settle by while nothing commands it
POSITION_SLACK = 0.005  # m an object may settle by
PROBE_TEXT = "pick up the red cup"


def _wrong(kind: Any) -> Any:
    """A value of another type than ``kind`` accepts."""
    return 12345 if kind is str else "wrong"


def _plausible(kind: Any) -> Any:
    """A value of roughly the right shape for ``kind`` (itself not necessarily right)."""
    if kind is str:
        return "x"
    origin = getattr(kind, "__origin__", kind)
    if origin in (list, tuple):
        return []
    if origin is dict or isinstance(origin, type) and issubclass(origin, msgspec.Struct):
        return {}
    return 0.0


def malformed(schema: str, rng: random.Random) -> bytes:
    """One payload that is not a valid ``schema`` message: each call picks one way to be wrong."""
    fields = {info.name: info.type for info in msgspec.structs.fields(TYPES[schema]) if info.required}
    base: dict[str, Any] = {name: _plausible(kind) for name, kind in fields.items()}
    ways: list[Callable[[], bytes]] = [
        lambda: rng.randbytes(rng.randrange(0, 64)),  # not msgpack at all
        lambda: b"",
        lambda: encode({"text": "cut short", **base})[: -rng.randrange(1, 4)],  # truncated
        lambda: msgpack.packb(rng.choice([[1, 2], 7, "text", None, True])),  # not a map
        lambda: msgpack.packb({"text": "no version"}),
        lambda: msgpack.packb({"v": rng.choice([0, 2, "1", None, 1.5]), **base}),
        lambda: b"\xc6\xff\xff\xff\xff",  # a 4 GiB bin header, no body
        lambda: b"\x91" * 5000,  # nested far too deep
        lambda: encode(
            {
                "pcm": {
                    "__ndarray__": True,
                    "dtype": rng.choice(["O", "bogus", "<f4"]),
                    "shape": [3, 5],
                    "data": b"\x00" * 7,
                },
                **base,
            }
        ),
    ]
    if fields:
        missing = rng.choice(list(fields))
        ways.append(lambda: encode({k: v for k, v in base.items() if k != missing}))
        ways.append(lambda: encode({**base, missing: _wrong(fields[missing])}))
    return rng.choice(ways)()


@dataclass
class Figures:
    """What one run sent, how fast, and what it found."""

    per_key: int
    streams: dict[str, float] = field(default_factory=dict)  # key -> messages per second
    queries: dict[str, float] = field(default_factory=dict)  # key -> requests per second
    accepted: dict[str, int] = field(default_factory=dict)  # queryable -> bad requests answered "ok"
    logged: dict[str, int] = field(default_factory=dict)  # key -> rejections the services logged
    problems: list[str] = field(default_factory=list)

    def lines(self) -> Iterator[str]:
        yield f"bad input: {self.per_key} per stream key and per queryable"
        yield "  (logged: rejections in the services' logs; a newest-only reader skips what it had no time for)"
        for key, rate in self.streams.items():
            yield f"  stream    {_suffix(key):<26} {rate:>8.0f} msg/s   logged {self.logged.get(key, 0):>6}"
        for key, rate in self.queries.items():
            yield (
                f"  queryable {_suffix(key):<26} {rate:>8.0f} req/s   logged {self.logged.get(key, 0):>6}   "
                f"answered ok: {self.accepted.get(key, 0)}"
            )
        yield "services alive, serving and unchanged" if not self.problems else "PROBLEMS:"
        yield from (f"  {problem}" for problem in self.problems)


def _suffix(key: str) -> str:
    return key.split("/", 2)[2]


_REJECTION = re.compile(r"(?:rejected|refused) (?:message|request) on (\S+?):")
_REJECTED_CLOUD = "rejected cloud: "  # perception checks clouds itself, and says so without the key


def logged_rejections(children: Sequence[ServiceProcess], cloud_key: str) -> dict[str, int]:
    """Rejections per key in the services' logs, once the services have worked through what was sent."""
    counts: dict[str, int] = {}
    previous = None
    deadline = time.monotonic() + 120
    while counts != previous and time.monotonic() < deadline:
        previous = counts
        time.sleep(0.5)
        counts = {}
        for child in children:
            text = child.log()
            for key in _REJECTION.findall(text):
                counts[key] = counts.get(key, 0) + 1
            if text.count(_REJECTED_CLOUD):
                counts[cloud_key] = counts.get(cloud_key, 0) + text.count(_REJECTED_CLOUD)
    return counts


def _snapshot(bus: Bus) -> dict[str, Any]:
    """The answers that must not change: the actions, a parse on the live world, perception's objects."""
    parse = bus.request(bus.keys.nlu_query("parse"), {"text": PROBE_TEXT}, reply=Parsed, timeout=10)
    actions = bus.request(bus.keys.executor_control("actions"), {"op": "list"}, reply=ActionList, timeout=10)
    return {"parse": parse, "actions": actions}


class SimView:
    """The simulator's newest robot state and ground truth, to tell whether the junk moved anything."""

    def __init__(self, bus: Bus) -> None:
        self.state: SimState | None = None
        self.truth: Truth | None = None
        bus.subscribe(bus.keys.sim_state, lambda m: setattr(self, "state", m), schema="sim_state", latest_only=True)
        bus.subscribe(bus.keys.truth, lambda m: setattr(self, "truth", m), schema="truth", latest_only=True)

    def now(self, timeout: float = 30.0) -> dict[str, Any]:
        """Joints, object positions, scene and pause flag, once both streams have been heard."""
        deadline = time.monotonic() + timeout
        while not (self.state and self.truth) and time.monotonic() < deadline:
            time.sleep(0.1)
        state, truth = self.state, self.truth
        return {
            "joints": dict(state.joints) if state else {},
            "objects": {o.id: list(o.position) for o in truth.objects} if truth else {},
            "scene": truth.scene if truth else None,
            "paused": state.paused if state else None,
            "sim_time": state.sim_time if state else None,
        }

    def changes(self, before: dict[str, Any]) -> list[str]:
        after = self.now()
        problems = [
            f"sim {name} changed: {before[name]!r} -> {after[name]!r}"
            for name in ("scene", "paused")
            if before[name] != after[name]
        ]
        if not after["sim_time"] or not before["sim_time"] or after["sim_time"] <= before["sim_time"]:
            problems.append("the simulation clock did not advance")
        moved = [
            name for name, q in before["joints"].items() if abs(after["joints"].get(name, q + 1) - q) > JOINT_SLACK
        ]
        if moved:
            problems.append(f"sim joints moved: {', '.join(sorted(moved))}")
        shifted = [
            oid
            for oid, where in before["objects"].items()
            if oid not in after["objects"]
            or max(abs(a - b) for a, b in zip(after["objects"][oid], where)) > POSITION_SLACK
        ]
        if shifted or set(after["objects"]) != set(before["objects"]):
            problems.append(
                f"sim objects changed: {sorted(set(shifted) | set(after['objects']) ^ set(before['objects']))}"
            )
        return problems


def _flood_stream(bus: Bus, key: str, schema: str, count: int, rng: random.Random) -> float:
    """Put ``count`` malformed payloads on ``key`` (blocking, so none is dropped before it arrives); msg/s."""
    publisher = bus.session.declare_publisher(key, congestion_control=zenoh.CongestionControl.BLOCK)
    started = time.perf_counter()
    try:
        for _ in range(count):
            publisher.put(malformed(schema, rng))
    finally:
        publisher.undeclare()
    return count / (time.perf_counter() - started)


def _flood_queryable(bus: Bus, key: str, count: int, rng: random.Random, window: int = 64) -> tuple[float, int]:
    """Send ``count`` bad requests, ``window`` at a time; returns (requests/s, how many were answered ok)."""
    refused = REFUSED[key.split("/", 2)[2]]
    pending: list[Any] = []
    accepted = 0

    def drain(handler: Any) -> int:
        return sum(reply.ok is not None and decode(reply.ok.payload.to_bytes()).get("ok") is True for reply in handler)

    started = time.perf_counter()
    for i in range(count):
        payload = encode(dict(rng.choice(refused))) if refused and i % 2 else malformed("request", rng)
        pending.append(bus.session.get(key, payload=payload, timeout=10))
        if len(pending) >= window:
            accepted += drain(pending.pop(0))
    accepted += sum(drain(handler) for handler in pending)
    return count / (time.perf_counter() - started), accepted


def check_services(bus: Bus, children: Sequence[ServiceProcess], before: dict[str, Any]) -> list[str]:
    """Alive, serving, unchanged, and no traceback in any log."""
    problems = []
    alive = bus.alive_services(timeout=2)
    for child in children:
        if child.exited() is not None or child.name not in alive:
            problems.append(f"{child.name} is down (exit code {child.exited()})")
        if "Traceback" in child.log():
            problems.append(f"{child.name} logged a traceback: see {child.log_path}")
    if not problems:
        after = _snapshot(bus)
        problems += [
            f"{name} changed: {before[name]!r} -> {after[name]!r}" for name in before if after[name] != before[name]
        ]
    return problems


def run(bus: Bus, children: Sequence[ServiceProcess], count: int, seed: int = 0) -> Figures:
    """Flood every key, then check the services (they must already be up on ``bus``'s namespace)."""
    rng = random.Random(seed)
    figures = Figures(count)
    made_up: list[Objects] = []

    def on_objects(message: Objects) -> None:
        if message.objects:
            made_up.append(message)

    bus.subscribe(bus.keys.objects, on_objects, schema="objects")
    heard: list[Utterance] = []  # utterances that pass the schema: only speech could have made them, from junk
    bus.subscribe(bus.keys.utterance, heard.append, schema="utterance")
    started = {child.name for child in children}
    sim = SimView(bus) if "sim" in started else None
    sim_before = sim.now() if sim else {}
    before = _snapshot(bus)
    for suffix, schema in STREAMS.items():
        key = f"pbd/{bus.keys.namespace}/{suffix}"
        figures.streams[key] = _flood_stream(bus, key, schema, count, rng)
    for suffix in REFUSED:
        if suffix.split("/", 1)[0] not in started:  # a service run elsewhere, or not at all
            continue
        key = f"pbd/{bus.keys.namespace}/{suffix}"
        figures.queries[key], figures.accepted[key] = _flood_queryable(bus, key, count, rng)
    figures.logged = logged_rejections(children, bus.keys.cloud)
    figures.problems = check_services(bus, children, before)
    if sim is not None:
        figures.problems += sim.changes(sim_before)
    figures.problems += [
        f"{_suffix(key)}: no service logged a rejection"
        for key in [*figures.streams, *figures.queries]
        if not figures.logged.get(key)
    ]
    figures.problems += [f"{key}: {n} bad requests were answered ok" for key, n in figures.accepted.items() if n]
    if made_up:
        figures.problems.append(f"perception published {len(made_up)} object lists from malformed clouds")
    if heard:
        figures.problems.append(f"{len(heard)} utterances were published from malformed audio: {heard[:3]!r}")
    return figures


def service_args(name: str, data_dir: Path) -> tuple[str, ...]:
    """The flags a service runs with under the fuzz (a private actions store; a simulator without a camera)."""
    if name == "executor":
        return ("--data-dir", str(data_dir))
    if name == "speech":
        return SPEECH_ARGS
    return SIM_ARGS if name == "sim" else ()


def start_services(bus: Bus, log_dir: Path, data_dir: Path, port: int) -> LocalStack:
    stack = LocalStack(bus, log_dir)
    session = loopback_options(bus.keys.namespace, port, listen=False).to_argv()
    for name in SERVICES:
        stack.start(name, session, *service_args(name, data_dir))
    return stack


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="hfpbd bench fuzz", description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=10_000, help="per stream key and per queryable")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    logging.getLogger("hfpbd.bus").setLevel(logging.ERROR)  # this session reads its own junk: no line per item
    namespace, port = "fuzz" + uuid.uuid4().hex[:8], free_port()
    with tempfile.TemporaryDirectory() as scratch, Bus(loopback_options(namespace, port, listen=True)) as bus:
        stack = start_services(bus, Path(scratch) / "logs", Path(scratch) / "data", port)
        try:
            started = time.perf_counter()
            figures = run(bus, stack.children, args.count, args.seed)
            elapsed = time.perf_counter() - started
        finally:
            stack.stop()
    for line in figures.lines():
        print(line)
    total = args.count * (len(figures.streams) + len(figures.queries))
    print(f"{total} bad messages and requests in {elapsed:.1f} s")
    return 1 if figures.problems else 0


if __name__ == "__main__":
    sys.exit(main())
