"""Every benchmark ``hfpbd bench`` names is there to run: its module imports and has a ``main``."""

from __future__ import annotations

import importlib

import pytest

from hfpbd.bench import BENCHMARKS

pytestmark = pytest.mark.unit


@pytest.mark.parametrize("name", sorted(BENCHMARKS))
def test_each_benchmark_named_has_its_module_and_main(name: str) -> None:
    module = importlib.import_module(BENCHMARKS[name])
    assert callable(getattr(module, "main", None)), f"hfpbd bench {name}: {BENCHMARKS[name]} has no main()"
