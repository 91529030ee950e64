"""Bad input at volume against every real service but the UI (``hfpbd bench fuzz`` with a smaller count)."""

from __future__ import annotations

from pathlib import Path

from hfpbd.fuzz import REFUSED, SERVICES, STREAMS, run, service_args
from tests.processes import Launcher, Network

PER_KEY = 500


def test_malformed_messages_and_bad_requests_leave_every_service_alive_serving_and_unchanged(
    network: Network, launcher: Launcher, tmp_path: Path
) -> None:
    children = [launcher.start(name, *service_args(name, tmp_path / "data")) for name in SERVICES]
    figures = run(network.hub, children, PER_KEY)
    assert not figures.problems, "\n".join(figures.lines())
    assert len(figures.streams) == len(STREAMS) and len(figures.queries) == len(REFUSED)
    for key in figures.queries:  # every request is answered, none is skipped
        assert figures.logged[key] >= PER_KEY // 2, (key, figures.logged)
    assert not any(figures.accepted.values())
