"""The executor's integration tests share one pattern: a real sim + perception + executor per module."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from tests.executor.stack import Stack


@pytest.fixture(scope="module")
def stack(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Stack]:
    """Started once per test module (tens of seconds), always closed."""
    running = Stack(tmp_path_factory.mktemp("logs"), tmp_path_factory.mktemp("data"))
    try:
        running.start()
        yield running
    finally:
        running.close()
