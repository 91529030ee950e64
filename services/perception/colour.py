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

CHROMATIC = ("red", "orange", "yellow", "green", "blue", "purple")
ACHROMATIC = ("white", "grey", "black")

# Upper hue bounds in OpenCV's 0-180 scale; hues from the last bound wrap to red.
HUE_BOUNDS = ((9, "red"), (21, "orange"), (35, "yellow"), (85, "green"), (128, "blue"), (163, "purple"))
MIN_SATURATION = 70  # below this a pixel is white, grey or black
MIN_VALUE = 45  # below this every pixel is black, whatever its hue
WHITE_VALUE = 185  # bright-quartile value above which a pale object is white
BLACK_VALUE = 70  # bright-quartile value below which it is black


@dataclass(frozen=True)
class ColourEstimate:
    word: str
    share: float  # fraction of pixels that voted for the word
    mean_rgb: tuple[int, int, int]


def colour_word(rgb: np.ndarray) -> ColourEstimate:
    """The colour word of a set of pixels ``rgb`` (N, 3) uint8."""
    if not len(rgb):
        return ColourEstimate("unknown", 0.0, (0, 0, 0))
    pixels = np.ascontiguousarray(rgb, dtype=np.uint8).reshape(-1, 1, 3)
    hsv = cv2.cvtColor(pixels, cv2.COLOR_RGB2HSV).reshape(-1, 3).astype(np.int32)
    hue, sat, val = hsv[:, 0], hsv[:, 1], hsv[:, 2]
    mean_rgb = tuple(int(round(c)) for c in rgb.reshape(-1, 3).mean(axis=0))
    chromatic = (sat >= MIN_SATURATION) & (val >= MIN_VALUE)
    if chromatic.mean() >= 0.4:
        words = np.searchsorted([b for b, _ in HUE_BOUNDS], hue[chromatic], side="right")
        votes = np.bincount(words, minlength=len(HUE_BOUNDS) + 1)
        votes[0] += votes[-1]  # the top of the hue circle is red again
        votes = votes[:-1]
        winner = int(votes.argmax())
        return ColourEstimate(HUE_BOUNDS[winner][1], float(votes[winner] / len(hsv)), mean_rgb)
    bright = float(np.percentile(val, 75))
    word = "white" if bright >= WHITE_VALUE else "black" if bright < BLACK_VALUE else "grey"
    return ColourEstimate(word, float(1.0 - chromatic.mean()), mean_rgb)
