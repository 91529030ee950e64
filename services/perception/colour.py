"""Colour words from pixel colours, in HSV.

Why HSV per pixel rather than the mean colour's largest channel: hue survives
shading (the shadowed side of a red cup is still red), and saturation and
value tell the achromatic words (white, grey, black) apart from the others,
which an argmax over R, G, B cannot. Each pixel votes; the share of the
winning vote is how sure we are.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

ACHROMATIC = ("white", "grey", "black")

# Upper hue bounds in OpenCV's 0-180 scale; hues from the last bound wrap to red.
HUE_BOUNDS = ((9, "red"), (21, "orange"), (35, "yellow"), (85, "green"), (128, "blue"), (163, "purple"))
CHROMATIC = tuple(word for _, word in HUE_BOUNDS)
MIN_SATURATION = 70  # below this a pixel is white, grey or black
MIN_VALUE = 45  # below this every pixel is black, whatever its hue
WHITE_VALUE = 185  # bright-quartile value above which a pale object is white
BLACK_VALUE = 70  # bright-quartile value below which it is black


@dataclass(frozen=True)
class ColourEstimate:
    word: str
    share: float  # fraction of pixels that voted for the word
    mean_rgb: tuple[int, int, int]


ACHROMATIC_CLASS = -1  # the class of a white, grey or black pixel in :func:`hue_classes`


def hue_classes(rgb: np.ndarray) -> np.ndarray:
    """Each pixel's class (N,): its hue word's index in ``CHROMATIC``, or ``ACHROMATIC_CLASS``.

    White, grey and black pixels share one class: which of the three a pale
    pixel is depends on its shading, not on the object it belongs to.
    """
    return _classes(_hsv(rgb))


def colour_word(rgb: np.ndarray) -> ColourEstimate:
    """The colour word of a set of pixels ``rgb`` (N, 3) uint8."""
    if not len(rgb):
        return ColourEstimate("unknown", 0.0, (0, 0, 0))
    hsv = _hsv(rgb)
    classes = _classes(hsv)
    red, green, blue = (int(round(c)) for c in rgb.reshape(-1, 3).mean(axis=0))
    mean_rgb = (red, green, blue)
    chromatic = classes != ACHROMATIC_CLASS
    if chromatic.mean() >= 0.4:
        votes = np.bincount(classes[chromatic], minlength=len(CHROMATIC))
        winner = int(votes.argmax())
        return ColourEstimate(CHROMATIC[winner], float(votes[winner] / len(hsv)), mean_rgb)
    bright = float(np.percentile(hsv[:, 2], 75))
    word = "white" if bright >= WHITE_VALUE else "black" if bright < BLACK_VALUE else "grey"
    return ColourEstimate(word, float(1.0 - chromatic.mean()), mean_rgb)


def _hsv(rgb: np.ndarray) -> np.ndarray:
    pixels = np.ascontiguousarray(rgb, dtype=np.uint8).reshape(-1, 1, 3)
    return cv2.cvtColor(pixels, cv2.COLOR_RGB2HSV).reshape(-1, 3).astype(np.int32)


def _classes(hsv: np.ndarray) -> np.ndarray:
    hue, sat, val = hsv[:, 0], hsv[:, 1], hsv[:, 2]
    words = np.searchsorted([b for b, _ in HUE_BOUNDS], hue, side="right") % len(CHROMATIC)  # past purple: red
    return np.where((sat >= MIN_SATURATION) & (val >= MIN_VALUE), words, ACHROMATIC_CLASS)
