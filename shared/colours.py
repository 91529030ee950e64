"""The colour of each colour word (DESIGN.md's words, but ``unknown``), as the simulator paints objects.

Why one table: the simulator paints with it, the synthetic scenes that test
perception render with it, and the screen draws an object with it when no
colour was measured; three tables had drifted apart, so perception was
tested on colours the simulator never shows. The values sit far apart in hue
(or in value for white, grey and black) so that perception's HSV classifier
tells them apart under the scene's lights.
"""

from __future__ import annotations

# colour word -> linear RGB, 0 to 1 (the simulator's material colour)
COLOURS: dict[str, tuple[float, float, float]] = {
    "red": (0.85, 0.08, 0.08),
    "green": (0.10, 0.65, 0.15),
    "blue": (0.08, 0.22, 0.85),
    "yellow": (0.95, 0.85, 0.08),
    "orange": (1.00, 0.45, 0.02),
    "purple": (0.50, 0.12, 0.70),
    "white": (0.95, 0.95, 0.95),
    "black": (0.06, 0.06, 0.06),
    "grey": (0.50, 0.50, 0.50),
}


def rgb8(word: str) -> tuple[int, int, int]:
    """The word's colour as 8-bit RGB (0 to 255), as a camera picture or a screen holds it."""
    red, green, blue = (round(channel * 255) for channel in COLOURS[word])
    return red, green, blue
