"""A minimal real service for bus tests: echoes messages and answers queries.

It runs through ``run_service`` exactly as the product's services do, so the
tests exercise the same session setup, liveliness and shutdown path.
"""

from __future__ import annotations

import argparse
import hashlib
import sys
import threading

from shared.bus import Bus
from shared.messages import Cloud, Utterance
from shared.service import run_service, wait_until_stopped

NAME = "echo"


def _body(bus: Bus, _args: argparse.Namespace, stop: threading.Event) -> None:
    keys = bus.keys
    out = bus.publisher(f"pbd/{keys.namespace}/test/out")

    def on_in(message: Utterance) -> None:
        out.put({"text": message.text})

    def on_cloud(message: Cloud) -> None:
        digest = hashlib.sha256(message.xyz.tobytes() + message.rgb.tobytes()).hexdigest()
        out.put({"digest": digest, "shape": list(message.xyz.shape)})

    bus.subscribe(f"pbd/{keys.namespace}/test/in", on_in, schema="utterance")
    bus.subscribe(keys.cloud, on_cloud, schema="cloud")
    bus.serve(f"pbd/{keys.namespace}/test/echo", lambda request: {"ok": True, "echo": request.get("text")})
    bus.serve(f"pbd/{keys.namespace}/test/fail", lambda request: 1 / 0)
    bus.serve(f"pbd/{keys.namespace}/test/stats", lambda request: {"ok": True, "rejected": sum(bus.rejected.values())})
    bus.declare_alive(NAME)
    wait_until_stopped(stop)


def main(argv: list[str] | None = None) -> int:
    return run_service(NAME, "bus test peer", _body, argv)


if __name__ == "__main__":
    sys.exit(main())
