"""Describing and grounding objects in words: one package for the NLU, the executor's narration and the speech grammar.

``labels`` (salient labels, grounding a bag of words), ``relational`` (a
relation to another object, both ways), ``refexp`` (the scene whose objects
are described, the one every reader uses), ``referring`` (the objects a
phrase means) and ``phrasing`` (a command said back in words).
"""
