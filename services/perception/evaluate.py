"""Score perceived objects against the simulator's ground truth.

Used by the accuracy tests and ``hfpbd bench perception`` alike, so both
measure the same thing: detections are paired with true objects by an optimal
assignment on centre distance (pairs farther apart than ``MAX_PAIRING`` count
as a miss plus a phantom), then centre error, per-axis size error and the
colour and type words are compared.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linear_sum_assignment

from services.perception.descriptors import Descriptor

MAX_PAIRING = 0.05  # m


@dataclass
class Score:
    found: int = 0
    missed: list[str] = field(default_factory=list)  # true ids with no detection
    phantoms: int = 0  # detections with no true object
    centre_errors: list[float] = field(default_factory=list)
    size_errors: list[float] = field(default_factory=list)  # |error| per axis
    wrong_words: list[str] = field(default_factory=list)  # "obj1: blue bowl seen as blue cup"

    def add(self, other: Score) -> None:
        self.found += other.found
        self.missed += other.missed
        self.phantoms += other.phantoms
        self.centre_errors += other.centre_errors
        self.size_errors += other.size_errors
        self.wrong_words += other.wrong_words

    def p95(self, errors: Sequence[float]) -> float:
        return float(np.percentile(errors, 95)) if len(errors) else 0.0


def score(detected: Sequence[Descriptor], truth: Sequence[dict]) -> Score:
    """Compare one frame's detections with the true objects of the same moment."""
    result = Score()
    if detected and truth:
        cost = np.array([[np.linalg.norm(d.position - np.asarray(t["position"])) for d in detected] for t in truth])
        rows, cols = linear_sum_assignment(cost)
        pairs = [(r, c) for r, c in zip(rows, cols) if cost[r, c] <= MAX_PAIRING]
    else:
        pairs = []
    paired_truth = {r for r, _ in pairs}
    result.missed = [t["id"] for k, t in enumerate(truth) if k not in paired_truth]
    result.phantoms = len(detected) - len(pairs)
    result.found = len(pairs)
    for r, c in pairs:
        true, seen = truth[r], detected[c]
        result.centre_errors.append(float(np.linalg.norm(seen.position - np.asarray(true["position"]))))
        result.size_errors += np.abs(seen.size - np.asarray(true["size"])).tolist()
        if (seen.color, seen.type) != (true["color"], true["type"]):
            result.wrong_words.append(f"{true['id']}: {true['color']} {true['type']} seen as {seen.color} {seen.type}")
    return result
