"""The sentences a person reads aloud to enrol their voice (``hfpbd speech enrol``), kept in this one place.

Why these: they are commands of the robot's own language, so the speech
adapted to is the speech the recogniser will hear, and together they hold
every phone the command language uses (ZH, the one English phone it lacks,
is never needed). None of them is a sentence of the speech benchmark's
corpus (:mod:`services.speech.corpus`), so the benchmark can measure the
adaptation's gain on sentences the person did not read. Twenty short
sentences take about two minutes to read, which is enough speech for one
global MLLR transform (a few hundred parameters) and little enough that
people finish it.
"""

from __future__ import annotations

PROMPTS: tuple[str, ...] = (
    "pick up the yellow bowl with your left hand",
    "point to the purple cup with your right hand",
    "look at the biggest box",
    "move your left hand above the orange plate",
    "place it next to the green box",
    "rotate your left hand clockwise",
    "raise your right arm thirteen centimetres",
    "where is the huge glass",
    "grab the smallest block with your left hand",
    "turn your right hand counterclockwise",
    "move your right arm away from the white cup",
    "put the red cube on top of the black dish",
    "switch to action four",
    "move both arms down fifteen centimetres",
    "close your right gripper and then open both hands",
    "stop executing",
    "scratch that",
    "open your left gripper",
    "move your left hand further forward",
    "what do you have in your hand",
)


def prompt_file(number: int) -> str:
    """The WAV file name for prompt ``number`` (counted from 1, as shown): ``prompt_01.wav``."""
    return f"prompt_{number:02d}.wav"
