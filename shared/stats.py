"""Small statistics helpers shared by the benchmarks."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def percentiles_ms(seconds: Sequence[float]) -> tuple[float, float]:
    """p50 and p99 of durations given in seconds, in milliseconds."""
    values = np.asarray(seconds, dtype=float) * 1000.0
    return float(np.percentile(values, 50)), float(np.percentile(values, 99))


def markdown_table(header: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    """A GitHub-style table, so benchmark output pastes straight into the README."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(cell) for cell in row) + " |" for row in rows]
    return "\n".join(lines)
