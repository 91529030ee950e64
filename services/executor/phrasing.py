"""Joining words into the worker's, the replays' and the skill runs' sentences.

``wording`` says what one step does; these two only list names and start a
sentence with one, and all three parts of the executor that talk about
several steps or objects need them alike.
"""

from __future__ import annotations


def listed(words: list[str], last: str = "and") -> str:
    """ "a", "a and b", "a, b and c" (or "a, b or c")."""
    return words[0] if len(words) == 1 else f"{', '.join(words[:-1])} {last} {words[-1]}"


def capital(text: str) -> str:
    """``text`` with its first letter a capital, to begin a sentence with an action's name."""
    return text[:1].upper() + text[1:]
