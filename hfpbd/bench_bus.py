"""``hfpbd bench bus``: the bus wrapper against raw eclipse-zenoh, two processes.

Measures, in the same run and on the same loopback link, (1) round-trip
latency of small messages (ping → pong) and (2) throughput of 640×480
xyz+rgb point clouds, once through :class:`shared.bus.Bus` on both ends and
once with plain zenoh publishers and channel subscribers carrying the very
same msgpack messages (encoded and decoded on both sides, as any user of
zenoh must). The ratio shows what the wrapper itself costs: schema
validation, typed publishers and the worker-thread hand-off. Raw and bus
rounds alternate so that background load falls on both alike.
"""

from __future__ import annotations

import argparse
import queue
import subprocess
import sys
import threading
import time
import uuid

import numpy as np
import zenoh

from shared.bus import Bus
from shared.codec import decode, encode
from shared.config import SessionOptions, free_port, loopback_options, zenoh_config
from shared.messages import Cloud, Ping, Request
from shared.stats import markdown_table, percentiles_ms

PINGS = 2000
CLOUDS = 60


def _cloud(rng: np.random.Generator) -> dict:
    return {
        "stamp": time.time(),
        "xyz": rng.normal(size=(480, 640, 3)).astype(np.float32),
        "rgb": rng.integers(0, 256, size=(480, 640, 3), dtype=np.uint8),
        "camera_pose": [0.0, 0.0, 1.5, 1.0, 0.0, 0.0, 0.0],
        "width": 640,
        "height": 480,
    }


# -- the other process ------------------------------------------------------
def _peer(namespace: str, port: int, impl: str) -> None:
    """Echo pings as pongs and, when asked, publish clouds as fast as they go."""
    options = loopback_options(namespace, port, listen=False)
    if impl == "bus":
        _bus_peer(options, namespace)
    else:
        _raw_peer(options, namespace)


def _bus_peer(options: SessionOptions, namespace: str) -> None:
    prefix = f"pbd/{namespace}/bench"
    with Bus(options) as bus:
        pong = bus.publisher(f"{prefix}/pong")
        clouds = bus.publisher(bus.keys.cloud, large=True)
        start = threading.Event()
        bus.subscribe(f"{prefix}/ping", lambda m: pong.put(Ping(i=m.i)), schema="ping")
        bus.subscribe(f"{prefix}/go", lambda m: start.set())
        bus.declare_alive("bench-peer")
        start.wait()
        message = _cloud(np.random.default_rng(0))
        for i in range(CLOUDS):
            message["stamp"] = float(i)
            clouds.put(Cloud(**message))
        time.sleep(5)


def _raw_peer(options: SessionOptions, namespace: str) -> None:
    prefix = f"pbd/{namespace}/bench"
    rng = np.random.default_rng(0)
    with zenoh.open(zenoh_config(options)) as session:
        pong = session.declare_publisher(f"{prefix}/pong")
        clouds = session.declare_publisher(
            f"pbd/{namespace}/sim/cloud", congestion_control=zenoh.CongestionControl.BLOCK
        )
        pings = session.declare_subscriber(f"{prefix}/ping", zenoh.handlers.FifoChannel(4096))
        go = session.declare_subscriber(f"{prefix}/go", zenoh.handlers.FifoChannel(4))
        token = session.liveliness().declare_token(f"pbd/{namespace}/alive/bench-peer")

        def echo() -> None:
            for sample in pings:
                pong.put(encode({"i": decode(sample.payload.to_bytes())["i"]}))

        threading.Thread(target=echo, daemon=True).start()
        go.recv()
        message = _cloud(rng)
        for i in range(CLOUDS):
            message["stamp"] = float(i)
            clouds.put(encode(message))
        time.sleep(5)
        token.undeclare()


# -- the measuring process ----------------------------------------------------
def _start_peer(namespace: str, port: int, impl: str) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "hfpbd.bench_bus", "--peer", impl, "--namespace", namespace, "--port", str(port)]
    )


def _wait_peer(bus: Bus) -> None:
    deadline = time.monotonic() + 30
    while "bench-peer" not in bus.alive_services(timeout=0.5):
        if time.monotonic() > deadline:
            raise RuntimeError("benchmark peer did not start")


def _measure(impl: str) -> tuple[list[float], float]:
    namespace, port = "bench" + uuid.uuid4().hex[:8], free_port()
    prefix = f"pbd/{namespace}/bench"
    with Bus(loopback_options(namespace, port, listen=True)) as bus:
        peer = _start_peer(namespace, port, impl)
        try:
            _wait_peer(bus)
            pongs: queue.Queue = queue.Queue()
            arrivals: list[float] = []
            done = threading.Event()

            def on_cloud(_message: object) -> None:
                arrivals.append(time.perf_counter())
                if len(arrivals) == CLOUDS:
                    done.set()

            if impl == "bus":
                ping = bus.publisher(f"{prefix}/ping")
                bus.subscribe(f"{prefix}/pong", pongs.put)
                bus.subscribe(bus.keys.cloud, on_cloud)
                send = lambda i: ping.put(Ping(i=i))  # noqa: E731
            else:
                session = bus.session
                raw_ping = session.declare_publisher(f"{prefix}/ping")
                raw_pongs = session.declare_subscriber(f"{prefix}/pong", zenoh.handlers.FifoChannel(4096))
                raw_clouds = session.declare_subscriber(bus.keys.cloud, zenoh.handlers.FifoChannel(256))

                def drain_pongs() -> None:
                    for sample in raw_pongs:
                        pongs.put(decode(sample.payload.to_bytes()))

                def drain_clouds() -> None:
                    for sample in raw_clouds:
                        on_cloud(decode(sample.payload.to_bytes()))

                threading.Thread(target=drain_pongs, daemon=True).start()
                threading.Thread(target=drain_clouds, daemon=True).start()
                send = lambda i: raw_ping.put(encode({"i": i}))  # noqa: E731
            for i in range(200):  # warm up routes and first-put costs
                send(i)
                pongs.get(timeout=10)
            rtts = []
            for i in range(PINGS):
                started = time.perf_counter()
                send(i)
                pongs.get(timeout=10)
                rtts.append(time.perf_counter() - started)
            bus.publish(f"{prefix}/go", Request())
            if not done.wait(120):
                raise RuntimeError(f"only {len(arrivals)} of {CLOUDS} clouds arrived")
            rate = (len(arrivals) - 1) / (arrivals[-1] - arrivals[0])
            return rtts, rate
        finally:
            peer.terminate()
            peer.wait(10)


def run(rounds: int) -> int:
    """Alternate raw and bus rounds so that load from other programs hits both alike."""
    rtts: dict[str, list[float]] = {"raw": [], "bus": []}
    rates: dict[str, list[float]] = {"raw": [], "bus": []}
    for _ in range(rounds):
        for impl in ("raw", "bus"):
            round_rtts, rate = _measure(impl)
            rtts[impl] += round_rtts
            rates[impl].append(rate)
    raw_p50, raw_p99 = percentiles_ms(rtts["raw"])
    bus_p50, bus_p99 = percentiles_ms(rtts["bus"])
    raw_rate, bus_rate = float(np.median(rates["raw"])), float(np.median(rates["bus"]))
    rows = [
        ("small message round trip p50 (ms)", f"{raw_p50:.3f}", f"{bus_p50:.3f}", f"{bus_p50 / raw_p50:.2f}"),
        ("small message round trip p99 (ms)", f"{raw_p99:.3f}", f"{bus_p99:.3f}", f"{bus_p99 / raw_p99:.2f}"),
        ("640×480 xyz+rgb clouds (Hz)", f"{raw_rate:.1f}", f"{bus_rate:.1f}", f"{bus_rate / raw_rate:.2f}"),
    ]
    print(markdown_table(("measure", "raw zenoh", "hfpbd bus", "bus / raw"), rows))
    overhead = bus_p50 / raw_p50 - 1
    print(f"\nlatency overhead at p50: {overhead:+.0%} (target ≤ +20%): {'PASS' if overhead <= 0.2 else 'MISS'}")
    print(f"cloud rate through the bus: {bus_rate:.1f} Hz (target ≥ 15 Hz): {'PASS' if bus_rate >= 15 else 'MISS'}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="hfpbd bench bus", description=__doc__.splitlines()[0])
    parser.add_argument("--peer", choices=("raw", "bus"), help=argparse.SUPPRESS)
    parser.add_argument("--namespace", help=argparse.SUPPRESS)
    parser.add_argument("--port", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--rounds", type=int, default=3, help="alternating raw/bus rounds (default: %(default)s)")
    args = parser.parse_args(argv)
    if args.peer:
        _peer(args.namespace, args.port, args.peer)
        return 0
    return run(args.rounds)


if __name__ == "__main__":
    sys.exit(main())
