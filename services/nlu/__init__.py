"""Situated language understanding: utterance + world state -> one command or a question.

The library (everything here except ``service.py`` and ``main.py``) has no bus
dependency, so the command line, the benchmarks and the service share exactly
the same model.
"""
