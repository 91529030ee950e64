"""When a frame the renderer is drawing can be read without stalling the simulator's loop.

Why learn it: reading a frame's pixels blocks until the renderer is done,
and while the loop blocks nothing else happens — no physics step, no stop
request. The renderer's time per frame depends on the machine, the
resolution and what is in view, so the loop learns it from its own reads:
a read that had to wait lengthens the wait by what it waited; a read that
did not shortens it a little, so the wait tracks the renderer from above.
"""

from __future__ import annotations

BLOCKED = 0.002  # s: a read that took longer than this had to wait for the renderer
SHRINK = 0.95  # the wait after a read that did not block: reads early by at most 5 % of a frame
SHORTEST = 0.005  # s
LONGEST = 0.5  # s: past this the loop reads anyway (a stalled renderer must not stop the clouds)


class RenderWait:
    """How long after a picture was taken to read it."""

    def __init__(self, initial: float = 0.06) -> None:
        self.wait = initial

    def ready(self, taken_at: float, now: float) -> bool:
        return now - taken_at >= self.wait

    def learn(self, read_took: float) -> None:
        """Adjust the wait from how long the last read took (wall seconds)."""
        self.wait = self.wait + read_took if read_took > BLOCKED else self.wait * SHRINK
        self.wait = min(max(self.wait, SHORTEST), LONGEST)
