"""Schemas of the messages on the bus, checked on every decode.

A schema names required fields and their types; extra fields are allowed (the
design notes welcome them). Each key of the design table maps to one schema so
that a subscriber only ever sees messages that have what it reads.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from shared.codec import MessageError, decode

Number = (int, float)
Array = np.ndarray

# field name -> accepted type(s)
SCHEMAS: dict[str, dict[str, Any]] = {
    "utterance": {"text": str},
    "say": {"text": str, "kind": str},
    "cloud": {"stamp": Number, "xyz": Array, "rgb": Array, "camera_pose": list},
    "sim_state": {"stamp": Number, "joints": dict, "ee": dict, "grippers": dict},
    "truth": {"stamp": Number, "objects": list},
    "sim_event": {"motion_id": str, "status": str, "message": str},
    "objects": {"stamp": Number, "objects": list},
    "nlu_result": {"kind": str, "utterance": str},
    "executor_state": {"stamp": Number, "robot": dict},
    "speech_audio": {"pcm": Array, "rate": int},
    "speech_ptt": {"on": bool},
    "request": {},
    "reply": {"ok": bool},
}

SAY_KINDS = ("narration", "error", "clarify", "info")


def validate(schema: str, message: dict[str, Any]) -> dict[str, Any]:
    """Check ``message`` against ``schema``; raise :class:`MessageError` naming the first problem."""
    fields = SCHEMAS[schema]
    for name, kind in fields.items():
        if name not in message:
            raise MessageError(f"{schema} message lacks field {name!r}")
        value = message[name]
        if isinstance(value, bool) and kind is not bool and bool not in (kind if isinstance(kind, tuple) else (kind,)):
            raise MessageError(f"{schema}.{name} must be {_type_name(kind)}, got bool")
        if not isinstance(value, kind):
            raise MessageError(f"{schema}.{name} must be {_type_name(kind)}, got {type(value).__name__}")
    if schema == "say" and message["kind"] not in SAY_KINDS:
        raise MessageError(f"say.kind must be one of {', '.join(SAY_KINDS)}, got {message['kind']!r}")
    if schema in ("objects", "truth"):
        for item in message["objects"]:
            if not isinstance(item, dict) or not isinstance(item.get("id"), str):
                raise MessageError(f"{schema}.objects items must be maps with a string id")
    return message


def decode_as(schema: str, payload: bytes | bytearray | memoryview) -> dict[str, Any]:
    """Decode a payload and validate it against ``schema``."""
    return validate(schema, decode(payload))


def _type_name(kind: Any) -> str:
    if isinstance(kind, tuple):
        return " or ".join(k.__name__ for k in kind)
    return kind.__name__
