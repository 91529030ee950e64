"""The objects a referring phrase means, in any scene: one reading shared by the NLU and the executor's replay.

The NLU's ``ground`` and the executor, when it finds again on replay the
object the user's words named, read a phrase the same way; the other
direction (the words that single an object out) is ``refexp.Scene.describe_all``.
"""

from __future__ import annotations

import numpy as np

from services.nlu.language import relational
from services.nlu.language.labels import Labels
from services.nlu.tokens import read


def ground_phrase(scene: Labels, text: str) -> np.ndarray:
    """P(object | ``text``), in the scene's object order (paper Fig. 3); relational phrases resolved first."""
    terms = relational.resolve(scene, read(text).terms, scene.last_object, phrase=True)
    return scene.ground(terms)
