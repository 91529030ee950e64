"""Referring expressions: the words that single each object out, and the scene every reader names objects in.

Why a layer of its own: most objects are singled out by colour, kind and
salient labels (``labels``); the rest by a relation to another object ("the
cup next to the box", ``relational``), which itself reads labels to name the
landmark. Describing sits above both, so neither imports this module: the
NLU, the executor's narration and the speech grammar import :class:`Scene`.
"""

from __future__ import annotations

from services.nlu.language import relational
from services.nlu.language.labels import Expression, Labels
from services.nlu.world import World


class Scene(Labels):
    """One world's labels, with each object's description computed once."""

    def __init__(self, world: World) -> None:
        super().__init__(world)
        self._descriptions: dict[int, Expression] = {}

    def describe(self, index: int) -> Expression:
        """The shortest expression that singles out object ``index`` (location first); computed once per world."""
        cached = self._descriptions.get(index)
        if cached is None:
            cached = self.plain(index)
            if not cached.unique:
                text = relational.describe(self, index)
                cached = Expression(text, True) if text is not None else cached
            self._descriptions[index] = cached
        return cached

    def describe_all(self) -> dict[str, str]:
        return {obj.id: self.describe(i).text for i, obj in enumerate(self.world.objects)}
