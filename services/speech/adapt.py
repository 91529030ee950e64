"""Speaker adaptation with SphinxTrain: read sentences in, one MLLR transform of the acoustic model out.

The steps are CMU Sphinx's "Adapting the default acoustic model": ``sphinx_fe``
turns each recording into the model's cepstra, ``bw`` aligns them to their
transcripts and collects the Gaussians' counts, ``mllr_solve`` estimates one
global linear transform of the means from those counts. PocketSphinx applies
the transform when it loads the model (its ``mllr`` setting), so an adapted
voice costs nothing at decoding time.

Why MLLR and not MAP: MAP re-estimates each Gaussian and needs far more
speech than a person reads in two minutes, and it would write a whole new
model; a global MLLR transform has a few hundred parameters, is estimated
well from twenty sentences and is one small file per person.

Why the tools run as programs: SphinxTrain is a set of Debian programs
(``sphinxtrain``, ``sphinxbase-utils``), not a library.
"""

from __future__ import annotations

import math
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from services.speech.audio import dither
from services.speech.sphinx_model import default_dictionary, default_model_dir, training_model

# where Debian and a source build put SphinxTrain's programs (they are not on PATH)
TOOL_DIRS = (Path("/usr/lib/sphinxtrain"), Path("/usr/local/lib/sphinxtrain"), Path("/usr/libexec/sphinxtrain"))
TOOLS = {"sphinx_fe": "sphinxbase-utils", "bw": "sphinxtrain", "mllr_solve": "sphinxtrain"}
TIMEOUT_S = 300.0
# front-end settings of the model's feat.params that sphinx_fe takes; the rest describe features for bw
FRONT_END_KEYS = ("lowerf", "upperf", "nfilt", "transform", "lifter", "remove_noise", "alpha", "wlen", "nfft", "ncep")
FEATURE_KEYS = ("feat", "svspec", "cmn", "agc", "varnorm")
CODEBOOK_MAPS = {"ptm": ".ptm.", "semi": ".semi.", "cont": ".cont."}  # bw's names for the kinds of model
MIN_FRAMES = 1000  # 10 s of aligned speech: below this a 39-dimensional transform is poorly determined
_ALIGNED_FIELDS = 12  # bw's "utt>" line for an aligned utterance ends with its log-likelihoods


class AdaptationError(RuntimeError):
    """Adaptation could not be done; the message says why and what to do."""


@dataclass(frozen=True)
class Reading:
    """One sentence as read: ``key`` names it in messages (``prompt 3``), ``pcm`` is 16 kHz int16."""

    key: str
    text: str
    pcm: np.ndarray


@dataclass(frozen=True)
class Adaptation:
    """What ``bw`` made of the readings, and where the transform went."""

    matrix: Path
    aligned: tuple[str, ...]  # keys of the readings used
    unaligned: tuple[str, ...]  # keys of readings whose audio did not fit their text (left out)
    frames: int
    loglik_per_frame: float


def find_tools() -> dict[str, Path]:
    """The SphinxTrain programs by name; raises naming the missing ones and their Debian packages."""
    found: dict[str, Path] = {}
    missing = []
    for name, package in TOOLS.items():
        path = shutil.which(name) or next((str(d / name) for d in TOOL_DIRS if (d / name).is_file()), None)
        if path is None:
            missing.append(f"{name} (Debian package {package})")
        else:
            found[name] = Path(path)
    if missing:
        raise AdaptationError(
            "voice enrolment needs SphinxTrain's tools, which are not installed: "
            + ", ".join(missing)
            + "; install them with 'apt-get install sphinxtrain sphinxbase-utils' (scripts/setup.sh does)"
        )
    return found


def feature_settings(model_dir: Path) -> dict[str, str]:
    """The model's feat.params as a dict without the dashes: how its training features were computed."""
    words = (model_dir / "feat.params").read_text().split()
    return {key.lstrip("-"): value for key, value in zip(words[::2], words[1::2])}


def _run(tool: Path, args: list[str], log: Path) -> str:
    """Run one tool, its output kept in ``log``; raises with the tool's own last error line."""
    try:
        result = subprocess.run(
            [str(tool), *args], capture_output=True, text=True, timeout=TIMEOUT_S, stdin=subprocess.DEVNULL
        )
    except subprocess.TimeoutExpired:
        raise AdaptationError(f"{tool.name} did not finish within {TIMEOUT_S:g} s") from None
    output = result.stdout + result.stderr
    log.write_text(output)
    if result.returncode != 0:
        errors = [line for line in output.splitlines() if "ERROR" in line] or output.strip().splitlines()
        raise AdaptationError(f"{tool.name} failed: {(errors or [f'exit code {result.returncode}'])[-1]}")
    return output


def _pronunciations(words: set[str], dictionary: Path) -> dict[str, str]:
    """Each word's first pronunciation in the recogniser's dictionary (alternatives are ``word(2)``)."""
    found: dict[str, str] = {}
    with dictionary.open() as lines:
        for line in lines:
            word, _, phones = line.strip().partition(" ")
            if word in words and word not in found:
                found[word] = phones.strip()
    missing = sorted(words - set(found))
    if missing:
        raise AdaptationError(f"no pronunciation in {dictionary.name} for: {', '.join(missing)}")
    return found


def solve_mllr(
    readings: list[Reading],
    matrix: Path,
    work: Path | None = None,
    model_dir: Path | None = None,
    dictionary: Path | None = None,
) -> Adaptation:
    """Estimate an MLLR transform for the speaker of ``readings`` and write it to ``matrix``.

    ``work`` keeps the intermediate files (cepstra, counts, each tool's log)
    for inspection; by default they go to a temporary folder. Readings ``bw``
    cannot align to their text are left out and named in the result; too
    little aligned speech raises.
    """
    tools = find_tools()
    model_dir = model_dir or default_model_dir()
    dictionary = dictionary or default_dictionary()
    if not readings:
        raise AdaptationError("no recordings to adapt to")
    if work is None:
        with tempfile.TemporaryDirectory(prefix="hfpbd-enrol-") as folder:
            return solve_mllr(readings, matrix, Path(folder), model_dir, dictionary)
    work.mkdir(parents=True, exist_ok=True)
    settings = feature_settings(model_dir)
    keys = [f"utt{n:03d}" for n in range(len(readings))]
    for key, reading in zip(keys, readings):
        (work / f"{key}.raw").write_bytes(dither(reading.pcm).astype("<i2").tobytes())
    (work / "utterances.fileids").write_text("".join(f"{key}\n" for key in keys))
    (work / "utterances.transcription").write_text(
        "".join(f"<s> {reading.text} </s> ({key})\n" for key, reading in zip(keys, readings))
    )
    words = {w for reading in readings for w in reading.text.split()}
    pronunciations = _pronunciations(words, dictionary)
    (work / "words.dict").write_text("".join(f"{w} {p}\n" for w, p in sorted(pronunciations.items())))

    front_end = [arg for key in FRONT_END_KEYS if key in settings for arg in (f"-{key}", settings[key])]
    # the recogniser decodes every frame, so no frame may be dropped as silence here either
    _run(
        tools["sphinx_fe"],
        [*front_end, "-remove_silence", "no", "-samprate", "16000", "-raw", "yes"]
        + ["-c", str(work / "utterances.fileids"), "-di", str(work), "-do", str(work), "-ei", "raw", "-eo", "mfc"],
        work / "sphinx_fe.log",
    )
    trained = training_model(work / "model", model_dir)
    kind = settings.get("model", "ptm")
    features = [arg for key in FEATURE_KEYS if key in settings for arg in (f"-{key}", settings[key])]
    counts = work / "counts"
    counts.mkdir(exist_ok=True)
    output = _run(
        tools["bw"],
        [
            "-moddeffn",
            str(trained / "mdef.txt"),
            "-mixwfn",
            str(trained / "mixture_weights"),
            "-meanfn",
            str(model_dir / "means"),
            "-varfn",
            str(model_dir / "variances"),
            "-tmatfn",
            str(model_dir / "transition_matrices"),
            "-ts2cbfn",
            CODEBOOK_MAPS.get(kind, ".cont."),
            *features,
            "-dictfn",
            str(work / "words.dict"),
            "-fdictfn",
            str(model_dir / "noisedict"),
            "-ctlfn",
            str(work / "utterances.fileids"),
            "-lsnfn",
            str(work / "utterances.transcription"),
            "-cepdir",
            str(work),
            "-accumdir",
            str(counts),
            "-timing",
            "no",
        ],  # fmt: skip
        work / "bw.log",
    )
    aligned, frames, loglik = _alignment(output)
    by_key = dict(zip(keys, readings))
    used = tuple(by_key[k].key for k in keys if k in aligned)
    left_out = tuple(by_key[k].key for k in keys if k not in aligned)
    if frames < MIN_FRAMES:
        raise AdaptationError(
            f"too little speech matched its sentence ({frames / 100:.1f} s, at least {MIN_FRAMES / 100:g} s needed)"
            + (f"; these did not fit their text: {', '.join(left_out)}" if left_out else "")
        )
    matrix.parent.mkdir(parents=True, exist_ok=True)
    solved = work / "mllr_matrix"
    _run(
        tools["mllr_solve"],
        ["-meanfn", str(model_dir / "means"), "-varfn", str(model_dir / "variances")]
        + ["-outmllrfn", str(solved), "-accumdir", str(counts)],
        work / "mllr_solve.log",
    )
    check_matrix(solved)
    shutil.copyfile(solved, matrix)
    return Adaptation(matrix, used, left_out, frames, loglik)


def _alignment(bw_output: str) -> tuple[set[str], int, float]:
    """From bw's log: the utterances it aligned, their frames, and the mean log-likelihood per frame.

    An aligned utterance's ``utt>`` line ends with its total and
    per-frame log-likelihoods; one that could not be aligned (its audio
    does not fit its words) stops after the counts of its phones.
    """
    aligned: set[str] = set()
    frames = 0
    total = 0.0
    for line in bw_output.splitlines():
        fields = line.split()
        if fields[:1] != ["utt>"] or len(fields) < _ALIGNED_FIELDS:
            continue
        aligned.add(fields[2])
        frames += int(fields[3])
        total += float(fields[-1])
    return aligned, frames, total / frames if frames else -math.inf


def check_matrix(path: Path) -> None:
    """Raise unless ``path`` is an MLLR transform PocketSphinx can apply: classes, streams, then per stream
    its length n, the n x n matrix, the n offsets and the n variance scales, all finite numbers."""
    try:
        numbers = path.read_text().split()
    except (OSError, UnicodeDecodeError) as exc:
        raise AdaptationError(f"cannot read the voice adaptation file {path}: {exc}") from None
    try:
        values = [float(v) for v in numbers]
        classes, streams = int(values[0]), int(values[1])
        at = 2
        for _ in range(classes * streams):
            n = int(values[at])
            block = values[at + 1 : at + 1 + n * n + 2 * n]
            if len(block) != n * n + 2 * n or not all(math.isfinite(v) for v in block):
                raise ValueError("a stream's transform is incomplete or not finite")
            at += 1 + n * n + 2 * n
        if at != len(values) or classes < 1 or streams < 1:
            raise ValueError("unexpected length")
    except (ValueError, IndexError) as exc:
        raise AdaptationError(f"{path} is not a usable MLLR transform ({exc}); enrol again") from None
