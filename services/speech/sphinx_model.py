"""The shipped acoustic model in the forms SphinxTrain reads: a text model definition and mixture weights.

Why a conversion: the pocketsphinx wheel's en-us model (and Debian's
``pocketsphinx-en-us``, the same files) is packed for decoding. Its model
definition is PocketSphinx's binary ``mdef`` and its mixture weights exist
only as ``sendump``, 8-bit quantised negative logarithms. SphinxTrain's
``bw`` must have a text model definition and real mixture weights to align
the enrolment speech and collect the Gaussian counts that MLLR solves from.
Both conversions are exact up to the quantisation of the weights (each
weight within about 10 % of the trained one, renormalised to sum to one),
which is what PocketSphinx itself decodes with, so the alignment ``bw``
computes is the decoder's own. The means and variances, which the MLLR
transform is estimated for, are used as shipped.

The layouts read here are the ones each file describes in its own header
(``BEGIN FILE FORMAT DESCRIPTION``).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pocketsphinx import get_model_path

BINARY_MDEF_MAGIC = b"BMDF"
S3_BYTE_ORDER = 0x11223344
LOG_BASE = 1.0001  # PocketSphinx's logarithm base; sendump holds -log(weight) shifted right by MIXW_SHIFT
MIXW_SHIFT = 10
WORD_POSITIONS = "ibes"  # within a word, at its beginning, at its end, a word of one phone
_HEADER_FIELDS = 10


class ModelFormatError(ValueError):
    """A model file is not in the layout this module reads; the message names the file."""


def default_model_dir() -> Path:
    """The en-us acoustic model inside the pocketsphinx wheel, which the recogniser decodes with."""
    return Path(get_model_path()) / "en-us" / "en-us"


def default_dictionary() -> Path:
    return Path(get_model_path()) / "en-us" / "cmudict-en-us.dict"


@dataclass(frozen=True)
class Phone:
    """One row of a model definition: a base phone, or a triphone with its contexts and word position."""

    base: str
    left: str  # "-" for a base phone
    right: str
    position: str  # one of WORD_POSITIONS, "-" for a base phone
    filler: bool
    tmat: int
    senones: tuple[int, ...]


@dataclass(frozen=True)
class ModelDefinition:
    phones: list[Phone]
    n_base: int
    n_senones: int
    n_ci_senones: int
    n_tmat: int


def _int32s(data: bytes, offset: int, count: int) -> tuple[int, ...]:
    return struct.unpack_from(f"<{count}i", data, offset)


def read_binary_mdef(path: Path) -> ModelDefinition:
    """Read PocketSphinx's binary model definition (little-endian, as shipped)."""
    data = path.read_bytes()
    if data[:4] != BINARY_MDEF_MAGIC:
        raise ModelFormatError(f"{path} is not a binary model definition (no {BINARY_MDEF_MAGIC!r} mark)")
    version, description = _int32s(data, 4, 2)
    if version != 1:
        raise ModelFormatError(f"{path}: binary model definition version {version}, only version 1 is read")
    offset = 12 + description
    n_ci, n_phone, n_emit, n_ci_sen, n_sen, n_tmat, n_sseq, _n_ctx, n_cd_tree, _sil = _int32s(
        data, offset, _HEADER_FIELDS
    )
    if n_emit <= 0:
        raise ModelFormatError(f"{path}: phones with different numbers of states are not supported")
    offset += 4 * _HEADER_FIELDS
    names = []
    for _ in range(n_ci):
        end = data.index(b"\0", offset)
        names.append(data[offset:end].decode("ascii"))
        offset = end + 1
    offset = (offset + 3) & ~3  # padding to a 4-byte boundary
    offset += 8 * n_cd_tree  # the triphone lookup tree is not needed for a flat listing
    entries = np.frombuffer(
        data, dtype=np.dtype([("ssid", "<i4"), ("tmat", "<i4"), ("attr", "u1", 4)]), count=n_phone, offset=offset
    )
    offset += 12 * n_phone
    (n_states,) = _int32s(data, offset, 1)  # the senone sequences are preceded by their length
    if n_states != n_sseq * n_emit:
        raise ModelFormatError(f"{path}: {n_states} senone-sequence entries, expected {n_sseq * n_emit}")
    offset += 4
    sequences = np.frombuffer(data, dtype="<u2", count=n_sseq * n_emit, offset=offset).reshape(n_sseq, n_emit)
    if offset + sequences.nbytes != len(data):
        raise ModelFormatError(f"{path}: {len(data) - offset - sequences.nbytes} bytes left over after the phones")
    phones = []
    for index, (ssid, tmat, attr) in enumerate(entries.tolist()):
        senones = tuple(int(s) for s in sequences[ssid])
        if index < n_ci:
            phones.append(Phone(names[index], "-", "-", "-", bool(attr[0]), tmat, senones))
        else:
            position, base, left, right = attr
            phones.append(Phone(names[base], names[left], names[right], WORD_POSITIONS[position], False, tmat, senones))
    return ModelDefinition(phones, n_ci, n_sen, n_ci_sen, n_tmat)


def text_mdef(definition: ModelDefinition) -> str:
    """The model definition in SphinxTrain's text format (version 0.3)."""
    n_emit = len(definition.phones[0].senones)
    lines = [
        "0.3",
        f"{definition.n_base} n_base",
        f"{len(definition.phones) - definition.n_base} n_tri",
        f"{len(definition.phones) * (n_emit + 1)} n_state_map",
        f"{definition.n_senones} n_tied_state",
        f"{definition.n_ci_senones} n_tied_ci_state",
        f"{definition.n_tmat} n_tied_tmat",
        "#",
        "# Columns definitions",
        "#base lft  rt p attrib tmat      ... state id's ...",
    ]
    for phone in definition.phones:
        attribute = "filler" if phone.filler else "n/a"
        states = " ".join(str(s) for s in phone.senones)
        lines.append(f"{phone.base} {phone.left} {phone.right} {phone.position} {attribute} {phone.tmat} {states} N")
    return "\n".join(lines) + "\n"


def read_sendump(path: Path) -> np.ndarray:
    """Mixture weights from a ``sendump`` file, as float32 [senone, feature stream, Gaussian], each row summing to 1."""
    data = path.read_bytes()
    offset = 0
    header: dict[str, str] = {}
    while True:
        (length,) = _int32s(data, offset, 1)
        offset += 4
        if length == 0:
            break
        if not 0 < length < 4096:
            raise ModelFormatError(f"{path}: not a sendump file (a header string of {length} bytes)")
        key, _, value = data[offset : offset + length - 1].decode("ascii", "replace").partition(" ")
        header[key] = value
        offset += length
    if int(header.get("cluster_count", "0")) != 0:
        raise ModelFormatError(f"{path}: clustered mixture weights are not supported")
    n_streams = int(header.get("feature_count", "1"))
    n_gaussians, n_senones = _int32s(data, offset, 2)
    offset += 8
    expected = n_streams * n_gaussians * n_senones
    if len(data) - offset != expected:
        raise ModelFormatError(f"{path}: {len(data) - offset} bytes of weights, expected {expected}")
    quantised = np.frombuffer(data, dtype=np.uint8, offset=offset).reshape(n_streams, n_gaussians, n_senones)
    weights = np.power(LOG_BASE, -(quantised.astype(np.float64) * (1 << MIXW_SHIFT)))
    weights /= weights.sum(axis=1, keepdims=True)
    return np.ascontiguousarray(weights.transpose(2, 0, 1), dtype=np.float32)


def write_mixture_weights(path: Path, weights: np.ndarray) -> None:
    """A SphinxTrain mixture-weight file (``s3`` header, version 1.0, with its checksum)."""
    dims = np.array(weights.shape + (weights.size,), dtype="<u4")
    body = np.concatenate([dims, np.ascontiguousarray(weights, dtype="<f4").view("<u4").ravel()])
    with path.open("wb") as out:
        out.write(b"s3\nversion 1.0\nchksum0 yes\nendhdr\n")
        out.write(struct.pack("<I", S3_BYTE_ORDER))
        out.write(body.tobytes())
        out.write(struct.pack("<I", s3_checksum(body)))


def s3_checksum(words: np.ndarray) -> int:
    """SphinxTrain's checksum over the 32-bit words after the byte-order mark: rotate the sum left by 20, add.

    A plain loop (about a second for two million weights): each step depends on the last.
    """
    total = 0
    for word in words.astype(np.uint64).tolist():
        total = ((((total << 20) | (total >> 12)) & 0xFFFFFFFF) + word) & 0xFFFFFFFF
    return total


def training_model(folder: Path, model_dir: Path | None = None) -> Path:
    """Write ``mdef.txt`` and ``mixture_weights`` for ``model_dir`` into ``folder``; return ``folder``."""
    model_dir = model_dir or default_model_dir()
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "mdef.txt").write_text(text_mdef(read_binary_mdef(model_dir / "mdef")))
    write_mixture_weights(folder / "mixture_weights", read_sendump(model_dir / "sendump"))
    return folder
