"""msgpack codec with a schema version and numpy arrays as raw bytes.

Arrays travel as a map ``{"__ndarray__": true, "dtype": "<f4", "shape": [...],
"data": <bytes>}`` so any msgpack implementation can read them; dtypes are
forced little-endian on the wire.
"""

from __future__ import annotations

from typing import Any

import msgpack
import msgspec
import numpy as np

SCHEMA_VERSION = 1
_ND_MARK = "__ndarray__"


class MessageError(ValueError):
    """A payload that is not a valid message of the expected schema."""


def _pack_default(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        wire = value.astype(value.dtype.newbyteorder("<"), copy=False) if value.dtype.byteorder == ">" else value
        return {
            _ND_MARK: True,
            "dtype": wire.dtype.str,
            "shape": list(wire.shape),
            "data": np.ascontiguousarray(wire).tobytes(),
        }
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (tuple, set, frozenset)):
        return list(value)
    if isinstance(value, msgspec.Struct):
        return _fields(value)
    raise TypeError(f"cannot encode {type(value).__name__} in a message")


def _unpack_hook(obj: dict) -> Any:
    if obj.get(_ND_MARK) is True:
        try:
            dtype = np.dtype(obj["dtype"])
            shape = tuple(int(n) for n in obj["shape"])
            data = obj["data"]
            if dtype.hasobject:
                raise MessageError("object arrays are not allowed")
            array = np.frombuffer(data, dtype=dtype)
            return array.reshape(shape)
        except MessageError:
            raise
        except Exception as exc:  # malformed array description
            raise MessageError(f"malformed array: {exc}") from exc
    return obj


def _fields(message: msgspec.Struct) -> dict[str, Any]:
    """A typed message's fields as the map the wire carries.

    Every field is sent (a null as null: the design's payloads say "or
    null", and tools reading the plain maps rely on the key), except in a
    type declared ``omit_defaults``, whose optional parts are sent only when
    given, as ``hfpbd nlu parse`` prints a result.
    """
    if not message.__struct_config__.omit_defaults:
        return {name: getattr(message, name) for name in message.__struct_fields__}
    return {
        field.name: getattr(message, field.name)
        for field in msgspec.structs.fields(message)
        if field.default is msgspec.NODEFAULT or getattr(message, field.name) != field.default
    }


def encode(message: dict[str, Any] | msgspec.Struct) -> bytes:
    """Encode a message (a typed one, or a map), stamping the schema version ``v`` if absent."""
    if isinstance(message, msgspec.Struct):
        message = _fields(message)
    if "v" not in message:
        message = {"v": SCHEMA_VERSION, **message}
    return msgpack.packb(message, default=_pack_default, use_bin_type=True)


def decode(payload: bytes | bytearray | memoryview) -> dict[str, Any]:
    """Decode and check the envelope: a map whose ``v`` is our schema version."""
    try:
        message = msgpack.unpackb(bytes(payload), object_hook=_unpack_hook, raw=False, strict_map_key=False)
    except MessageError:
        raise
    except Exception as exc:
        raise MessageError(f"not msgpack: {exc}") from exc
    if not isinstance(message, dict):
        raise MessageError(f"expected a map, got {type(message).__name__}")
    version = message.get("v")
    if version != SCHEMA_VERSION:
        raise MessageError(f"schema version {version!r} is not {SCHEMA_VERSION}")
    return message
