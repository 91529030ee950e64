"""Message codec and schema validation."""

from __future__ import annotations

import msgpack
import numpy as np
import pytest

from shared.codec import SCHEMA_VERSION, MessageError, decode, encode
from shared.messages import decode_as, validate


@pytest.mark.parametrize("dtype", ["<f4", "<f8", "u1", "<u2", "<i4", ">f4", ">i8"])
def test_array_round_trip_is_exact_and_little_endian(dtype: str) -> None:
    array = (np.arange(24).reshape(2, 3, 4) * 3).astype(dtype)
    out = decode(encode({"a": array}))["a"]
    assert out.shape == (2, 3, 4)
    assert out.dtype.byteorder in ("<", "|", "=")
    np.testing.assert_array_equal(out, array)


def test_envelope_carries_schema_version() -> None:
    assert decode(encode({"text": "hi"})) == {"v": SCHEMA_VERSION, "text": "hi"}


@pytest.mark.parametrize("payload, reason", [
    (b"", "not msgpack"),
    (msgpack.packb([1, 2]), "expected a map"),
    (msgpack.packb({"v": 99}), "schema version 99"),
    (msgpack.packb({"text": "no version"}), "schema version None"),
    (msgpack.packb({"v": 1, "a": {"__ndarray__": True, "dtype": "<f4", "shape": [5], "data": b"abc"}}), "malformed array"),
    (msgpack.packb({"v": 1, "a": {"__ndarray__": True, "dtype": "|O", "shape": [1], "data": b"12345678"}}), "object arrays"),
])
def test_bad_payloads_raise_message_error(payload: bytes, reason: str) -> None:
    with pytest.raises(MessageError, match=reason):
        decode(payload)


@pytest.mark.parametrize("schema, message, reason", [
    ("say", {"text": "hi"}, "lacks field 'kind'"),
    ("say", {"text": "hi", "kind": "shout"}, "say.kind must be one of"),
    ("utterance", {"text": 5}, "must be str"),
    ("objects", {"stamp": 1.0, "objects": [{"color": "red"}]}, "string id"),
    ("cloud", {"stamp": True, "xyz": np.zeros(3), "rgb": np.zeros(3), "camera_pose": []}, "got bool"),
])
def test_schema_validation_names_the_problem(schema: str, message: dict, reason: str) -> None:
    with pytest.raises(MessageError, match=reason):
        validate(schema, message)


def test_decode_as_accepts_valid_message_with_extra_fields() -> None:
    message = decode_as("say", encode({"text": "Picking up the red cup.", "kind": "narration", "extra": 1}))
    assert message["extra"] == 1


def test_unencodable_value_is_refused() -> None:
    with pytest.raises(TypeError, match="cannot encode object"):
        encode({"x": object()})
