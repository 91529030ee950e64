"""A fresh settled look at the table, asked of the perception service.

The procedures ask for one before a pick-up is refused, and a replay after
each step it checks; both need the same answer to "perception stopped"
versus "perception is slow", which only the liveliness watch can tell, so
the look and that watch live together here.
"""

from __future__ import annotations

import threading
import time

from services.executor import wording
from services.executor.procedures import StepFailed
from services.executor.scene import Scene
from shared.bus import Bus, BusTimeout, RemoteError
from shared.messages import PerceivedObject, RecordReply

RECORD_TIMEOUT = 15.0
CUT_SHORT_MARGIN = 2.0  # seconds: a request unanswered this long before its timeout was ended by its answerer going


class Perception:
    """Takes fresh looks into ``scene``; a look that changed the objects marks the reach map ``stale``."""

    def __init__(self, bus: Bus, scene: Scene, stale: threading.Event) -> None:
        self.bus = bus
        self.scene = scene
        self.stale = stale
        self.losses = 0  # times perception's token vanished: one that died while asked is no mystery

    def alive(self, service: str, alive: bool) -> None:
        """A liveliness change (``bus.watch_alive``): count perception's losses."""
        if service == "perception" and not alive:
            self.losses += 1

    def record(self) -> list[PerceivedObject]:
        """A fresh settled observation from perception, taken into the scene at once.

        Unanswered, it says whether perception stopped while asked (its
        token went, it is gone, or the request was ended early by its going)
        or is merely not answering.

        A reply that does not fit its type (an object with a field out of
        range) is as good as perception failing: the step stops and says so.
        """
        losses, asked = self.losses, time.monotonic()
        try:
            reply = self.bus.request(self.bus.keys.record, {}, reply=RecordReply, timeout=RECORD_TIMEOUT)
        except BusTimeout as exc:
            # a request that ends unanswered well before its time lost the one who was to answer: the router
            # closes it when that service goes, sometimes before its liveliness token is seen to go (or, the
            # launcher being quick, after a new one is back)
            cut_short = time.monotonic() - asked < RECORD_TIMEOUT - CUT_SHORT_MARGIN
            if cut_short or self.losses != losses or "perception" not in self.bus.alive_services(timeout=0.5):
                raise StepFailed(
                    "I couldn't finish looking at the table: the perception service stopped, so it was interrupted."
                ) from exc
            raise StepFailed("I can't see anything: the perception service is not answering.") from exc
        except RemoteError as exc:  # MalformedReply included
            raise StepFailed(wording.sentence(f"I couldn't get a clear view of the table: {exc}")) from exc
        if self.scene.update_objects(reply.objects, reply.table):
            self.stale.set()
        return reply.objects
