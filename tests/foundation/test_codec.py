"""Message codec and schema validation."""

from __future__ import annotations

import msgpack
import numpy as np
import pytest

from shared.codec import SCHEMA_VERSION, MessageError, decode, encode
from shared.messages import ExecutorState, Say, decode_typed, typed


@pytest.mark.parametrize("dtype", ["<f4", "<f8", "u1", "<u2", "<i4", ">f4", ">i8"])
def test_array_round_trip_is_exact_and_little_endian(dtype: str) -> None:
    array = (np.arange(24).reshape(2, 3, 4) * 3).astype(dtype)
    out = decode(encode({"a": array}))["a"]
    assert out.shape == (2, 3, 4)
    assert out.dtype.byteorder in ("<", "|", "=")
    np.testing.assert_array_equal(out, array)


def test_envelope_carries_schema_version() -> None:
    assert decode(encode({"text": "hi"})) == {"v": SCHEMA_VERSION, "text": "hi"}


@pytest.mark.parametrize(
    "payload, reason",
    [
        (b"", "not msgpack"),
        (msgpack.packb([1, 2]), "expected a map"),
        (msgpack.packb({"v": 99}), "schema version 99"),
        (msgpack.packb({"text": "no version"}), "schema version None"),
        (
            msgpack.packb({"v": 1, "a": {"__ndarray__": True, "dtype": "<f4", "shape": [5], "data": b"abc"}}),
            "malformed array",
        ),
        (
            msgpack.packb({"v": 1, "a": {"__ndarray__": True, "dtype": "|O", "shape": [1], "data": b"12345678"}}),
            "object arrays",
        ),
    ],
)
def test_bad_payloads_raise_message_error(payload: bytes, reason: str) -> None:
    with pytest.raises(MessageError, match=reason):
        decode(payload)


@pytest.mark.parametrize(
    "schema, message, reason",
    [
        ("say", {"text": "hi"}, "missing required field `kind`"),
        ("say", {"text": "hi", "kind": "shout"}, r"Invalid enum value 'shout' - at `\$.kind`"),
        ("utterance", {"text": 5}, r"Expected `str`, got `int` - at `\$.text`"),
        ("objects", {"stamp": 1.0, "objects": [{"color": "red"}]}, "missing required field `id`"),
        ("cloud", {"stamp": True, "xyz": np.zeros(3), "rgb": np.zeros(3), "camera_pose": [0.0] * 7}, "got `bool`"),
        ("cloud", {"stamp": 1.0, "xyz": [0.0], "rgb": np.zeros(3), "camera_pose": [0.0] * 7}, "xyz must be an array"),
        # nested fields are checked too, and the problem is located
        (
            "objects",
            {"stamp": 1.0, "objects": [{"id": "obj0", "position": [0.6, "left", 0.8], "size": [0.1] * 3}]},
            r"at `\$.objects\[0\].position\[1\]`",
        ),
        ("objects", {"stamp": 1.0, "objects": [{"id": "obj0", "position": [0.6, 0.1], "size": [0.1] * 3}]}, "length 3"),
        (
            "sim_state",
            {"stamp": 1.0, "joints": {"a": 0.1}, "ee": {}, "grippers": {"right": {"width": "wide"}}},
            r"at `\$.grippers\[...\].width`",
        ),
        (
            "executor_state",
            {"stamp": 1.0, "robot": {"can_move": {"right": {"up": "yes"}}}},
            r"got `str` - at `\$.robot.can_move\[...\]\[...\]`",
        ),
        (
            "truth",
            {"stamp": 1.0, "objects": [{"id": 3, "position": [0.0] * 3, "size": [0.0] * 3}]},
            r"at `\$.objects\[0\].id`",
        ),
    ],
)
def test_schema_validation_names_the_problem(schema: str, message: dict, reason: str) -> None:
    with pytest.raises(MessageError, match=reason):
        typed(schema, message)


def test_a_message_with_extra_fields_decodes_to_its_type() -> None:
    message = decode_typed("say", encode({"text": "Picking up the red cup.", "kind": "narration", "extra": 1}))
    assert isinstance(message, Say) and message.text == "Picking up the red cup." and message.kind == "narration"


def test_unencodable_value_is_refused() -> None:
    with pytest.raises(TypeError, match="cannot encode object"):
        encode({"x": object()})


def test_typed_message_reads_as_attributes() -> None:
    state = typed(
        "executor_state",
        {"stamp": 1.0, "robot": {"grippers": {"right": "holding"}, "action": 2, "progress": {"step": 1, "of": 3}}},
    )
    assert isinstance(state, ExecutorState)
    assert state.robot.grippers["right"] == "holding"
    assert state.robot.progress is not None and state.robot.progress.of == 3
    assert state.robot.holding == {}
