"""Split a cluster where one object stands on another of a different colour.

Why: a cup put on a plate or on a box touches it, so the image links that
follow one surface (:mod:`services.perception.segment`) join the two into
one cluster: a white "bowl" 11.5 cm tall where a red cup stands on a plate,
or a red cup 16 cm tall and no box where it stands on one. Heights alone do
not tell them apart, colour does: every pixel has a hue class (white, grey
and black pixels share one, since which of them a pale pixel is depends on
its shading). A cluster is split only where its colour classes lie one
above the other, because a single object shows more than one class too, its
shadowed inside darker than its outside, but over its whole height, not
stacked.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from services.perception.colour import hue_classes

MIN_SHARE = 0.05  # of a cluster's points: a colour class smaller than this is edge blending, not an object
STACK_TOLERANCE = 0.015  # m the lower object's top may reach above the upper object's bottom (noise, rims)
MIN_RAISE = 0.01  # m above the table the upper object's bottom must be: on the table both would stand side by side
LOW, HIGH = 5, 95  # percentiles taken for a class's bottom and top, robust to stray points


@dataclass(frozen=True)
class Piece:
    """Indices of one object's points; ``raised``: it stands on another piece, so its bottom is its own."""

    members: np.ndarray
    raised: bool = False


def split_stacked(height: np.ndarray, rgb: np.ndarray, groups: list[np.ndarray], min_points: int) -> list[Piece]:
    """The objects in ``groups`` (index arrays into ``height`` and ``rgb``), stacked ones apart.

    ``height`` is each point's height above the table.
    """
    pieces: list[Piece] = []
    for members in groups:
        pieces += _layers(height[members], hue_classes(rgb[members]), members, min_points)
    return pieces


def _layers(height: np.ndarray, classes: np.ndarray, members: np.ndarray, min_points: int) -> list[Piece]:
    """One piece per layer of colour classes, from the table up; the whole cluster when nothing is stacked."""
    labels, counts = np.unique(classes, return_counts=True)
    big = labels[counts >= max(min_points, MIN_SHARE * len(members))]
    if len(big) < 2:
        return [Piece(members)]
    spans = {int(c): (np.percentile(height[classes == c], LOW), np.percentile(height[classes == c], HIGH)) for c in big}
    layers: list[list[int]] = []
    for c in sorted(spans, key=lambda c: spans[c][0]):
        top_below = max((spans[k][1] for k in layers[-1]), default=-np.inf) if layers else -np.inf
        bottom = spans[c][0]
        if layers and (bottom < MIN_RAISE or top_below > bottom + STACK_TOLERANCE):
            layers[-1].append(c)  # beside or inside what is below, not on it
        else:
            layers.append([c])
    if len(layers) < 2:
        return [Piece(members)]
    layer_of = np.full(len(members), -1)
    for k, layer in enumerate(layers):
        layer_of[np.isin(classes, layer)] = k
    lows = np.array([min(spans[c][0] for c in layer) for layer in layers])
    highs = np.array([max(spans[c][1] for c in layer) for layer in layers])
    stray = layer_of < 0  # pixels of a minor class: the layer whose heights they are among
    at = height[stray, None]
    layer_of[stray] = np.maximum(lows[None, :] - at, at - highs[None, :]).argmin(axis=1)
    return [Piece(members[layer_of == k], raised=k > 0) for k in range(len(layers))]
