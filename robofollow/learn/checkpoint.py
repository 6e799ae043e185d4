"""A baseline checkpoint folder:

    policy.json    what the network is and how to feed it (architecture, vocabulary,
                   normalisation, actions executed per chunk) and how it
                   was trained (options, dataset, steps, wall time)
    params.npz     the network's parameters
    optimizer.npz  Adam's moments and step (only to resume training; published checkpoints
                   leave it out)
    training.jsonl one line per logged step: loss, validation loss, samples/s

Files are written to a temporary name and renamed, so an interrupted write leaves the previous
checkpoint intact.
"""

from __future__ import annotations

import json
import math
import os
import zipfile
import zlib
from dataclasses import MISSING, dataclass, fields
from functools import cache
from pathlib import Path

import numpy as np
from pydantic import TypeAdapter, ValidationError

from robofollow.errors import RoboFollowError, did_you_mean, error_text
from robofollow.files import (
    file_problem,
    key_problem,
    number_problem,
    read_json_object,
    shown,
    write_json_atomic,
)
from robofollow.learn.model import ACTION_WIDTH, OBJECT_FIELDS, Architecture, init
from robofollow.learn.options import KINDS
from robofollow.learn.tokens import MAX_TOKENS

FORMAT = "robofollow-baseline/1"
PREFIX = "baseline:"  # --policy baseline:NAME names a shipped checkpoint


class CheckpointError(RoboFollowError):
    """A folder that is not a usable baseline checkpoint."""


@dataclass(frozen=True)
class Checkpoint:
    arch: Architecture
    vocab: list[str]
    normalization: dict[str, np.ndarray]  # state_mean, state_std, action_mean, action_std
    execute: int  # actions of each predicted chunk executed before the next query
    params: dict[str, np.ndarray]
    training: dict  # options and cost

    def meta(self) -> dict:
        return {"format": FORMAT, "architecture": self.arch.to_dict(), "vocab": self.vocab,
                "normalization": {k: v.tolist() for k, v in self.normalization.items()},
                "execute": self.execute, "training": self.training}


def is_checkpoint(path: str | Path) -> bool:
    """Whether a folder holds a policy.json, of any kind (loading says what is wrong with one
    that is not a file)."""
    return os.path.lexists(Path(path) / "policy.json")


def save(folder: Path, checkpoint: Checkpoint, optimizer: dict[str, np.ndarray] | None = None
         ) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    _atomic(folder / "params.npz", lambda f: np.savez(f, **checkpoint.params))
    if optimizer is not None:
        _atomic(folder / "optimizer.npz", lambda f: np.savez(f, **optimizer))
    write_json_atomic(folder / "policy.json", checkpoint.meta())


# -- reading a checkpoint back, checked: a bad file is a CheckpointError naming it and the field

META_KEYS = ("format", "architecture", "vocab", "normalization", "execute", "training")
MAX_POLICY_BYTES = 16 * 1024 * 1024  # policy.json: the shipped ones are under 5 KB
MAX_PARAMETERS = 64 * 1024 * 1024  # values the architecture may ask of params.npz (256 MB as
#   float32); the shipped baselines hold under 0.9 M (hidden 512, embed 64)
MAX_PARAMS_BYTES = 8 * MAX_PARAMETERS + (1 << 20)  # params.npz: MAX_PARAMETERS values as
#   float64 (training writes float32) and the archive's headers; the shipped ones are 3.1-3.5 MB
MAX_OPTIMIZER_BYTES = 2 * MAX_PARAMS_BYTES  # optimizer.npz: Adam's two moments of every
#   parameter and the step; twice params.npz (about 7 MB for a network of the shipped size)
NORMALIZED = {"state": ACTION_WIDTH, "action": ACTION_WIDTH, "objects": OBJECT_FIELDS}


def load(folder: Path) -> Checkpoint:
    """The checkpoint in `folder`, every part checked against policy.json's architecture."""
    path = folder / "policy.json"
    meta = _policy(path)
    arch = _architecture(path, meta["architecture"])
    vocab = _vocab(path, meta["vocab"], arch)
    normalization = _normalization(path, meta["normalization"], arch)
    execute = meta["execute"]
    if isinstance(execute, bool) or not isinstance(execute, int) or not 1 <= execute <= arch.chunk:
        raise CheckpointError(f"{path}: execute is {shown(execute)}, not a whole number from 1 "
                              f"to the chunk ({arch.chunk})")
    if not isinstance(meta["training"], dict):
        raise CheckpointError(f"{path}: training is {shown(meta['training'])}, not an object")
    params = _params(folder / "params.npz", {name: array.shape for name, array in
                                             init(arch, 0).items()})
    return Checkpoint(arch, vocab, normalization, execute, params, meta["training"])


def _policy(path: Path) -> dict:
    """policy.json: a JSON object with META_KEYS, in FORMAT."""
    meta, problem = read_json_object(path, MAX_POLICY_BYTES)
    if problem:
        raise CheckpointError(f"{path}: {problem} (a baseline checkpoint's policy.json "
                              "expected)")
    if "format" in meta and meta["format"] != FORMAT:
        raise CheckpointError(f"{path}: format {meta['format']!r}, expected {FORMAT!r}")
    _keys(path, meta, META_KEYS)
    return meta


def _keys(path: Path, data: dict, required, optional=(), where: str = "") -> None:
    found = key_problem(data, required, optional)
    if found is not None:
        kind, key = found
        if kind == "missing":
            raise CheckpointError(f"{path}: {where}no {shown(key)}")
        hint = did_you_mean(key, (*required, *optional))
        raise CheckpointError(f"{path}: {where}unknown key {shown(key)}"
                              f"{'; ' + hint if hint else ''}")


_adapter = cache(TypeAdapter)  # a dataclass's validator, made once


def validated(path: Path, kind: type, data, where: str):
    """policy.json's object at `where` as the dataclass `kind`: its fields (those without a
    default required) and no others, each of its type (strictly: no bool for a number);
    else a CheckpointError naming the field."""
    if not isinstance(data, dict):
        raise CheckpointError(f"{path}: {where} is {shown(data)}, not an object")
    _keys(path, data, [f.name for f in fields(kind) if f.default is MISSING],
          [f.name for f in fields(kind) if f.default is not MISSING], f"{where}: ")
    try:
        return _adapter(kind).validate_json(json.dumps(data), strict=True)
    except ValidationError as error:
        first = error.errors()[0]
        field = ".".join(map(str, first["loc"]))
        raise CheckpointError(f"{path}: {where}.{field} is {shown(first['input'])}: "
                              f"{first['msg'][:1].lower() + first['msg'][1:]}") from None


def _architecture(path: Path, data) -> Architecture:
    """The architecture: Architecture's fields of their types, in range, and a network of at
    most MAX_PARAMETERS values."""
    arch = validated(path, Architecture, data, "architecture")
    problem = _architecture_problem(arch)
    if problem:
        raise CheckpointError(f"{path}: architecture.{problem}")
    if _parameters_at_most(arch) > MAX_PARAMETERS:
        raise CheckpointError(f"{path}: architecture describes a network of up to "
                              f"{_parameters_at_most(arch):,} parameters, over the "
                              f"{MAX_PARAMETERS:,} a checkpoint may have")
    return arch


def _architecture_problem(arch: Architecture) -> str | None:
    if arch.kind not in KINDS:
        return f"kind is {shown(arch.kind)}, not one of {', '.join(KINDS)}"
    for index, camera in enumerate(arch.cameras):
        if not camera or camera in arch.cameras[:index]:
            return f"cameras[{index}] is {shown(camera)}: empty, or named twice"
    if not arch.channels:
        return "channels is empty: the network has no layer"
    for field in ("kernels", "strides"):
        if len(getattr(arch, field)) != len(arch.channels):
            return (f"{field} has {len(getattr(arch, field))} layers, but channels has "
                    f"{len(arch.channels)}")
    wholes = {"vocab_size": [arch.vocab_size], "chunk": [arch.chunk], "embed": [arch.embed],
              "hidden": [arch.hidden], "channels": arch.channels, "kernels": arch.kernels,
              "strides": arch.strides, "image_shape": arch.image_shape if arch.cameras else ()}
    for field, values in wholes.items():
        for value in values:
            if value < 1:
                return f"{field} holds {value}, not a whole number from 1"
    return None


def _parameters_at_most(arch: Architecture) -> int:
    """At least as many values as init(arch) draws (every layer at the widest and largest
    kernel): a bound checked before the parameters are made."""
    width, kernel, d, hidden = max(arch.channels), max(arch.kernels), arch.embed, arch.hidden
    cameras = len(arch.cameras)
    convolutions = cameras * len(arch.channels) * (kernel * kernel * max(width, 3) + 1) * width
    film = cameras * (d + 1) * 2 * width
    objects = (OBJECT_FIELDS + 7 * d + 7) * d
    tokens = (arch.vocab_size + MAX_TOKENS + 8 * d + 8) * d
    trunk = (cameras * 3 * width + 3 * d + 2 * ACTION_WIDTH + 2 * hidden + 3
             + arch.chunk * ACTION_WIDTH) * hidden
    return convolutions + film + objects + tokens + trunk + arch.chunk * ACTION_WIDTH


def _vocab(path: Path, vocab, arch: Architecture) -> list[str]:
    if not (isinstance(vocab, list) and all(isinstance(word, str) for word in vocab)):
        raise CheckpointError(f"{path}: vocab is {shown(vocab)}, not a list of words")
    if len(vocab) != arch.vocab_size:
        raise CheckpointError(f"{path}: vocab holds {len(vocab)} words, but "
                              f"architecture.vocab_size is {arch.vocab_size}")
    return vocab


def _normalization(path: Path, data, arch: Architecture) -> dict[str, np.ndarray]:
    """Each normalised part's mean and standard deviation: finite, the deviations above 0, as
    many as the part has values."""
    if not isinstance(data, dict):
        raise CheckpointError(f"{path}: normalization is {shown(data)}, not an object")
    parts = [part for part in NORMALIZED if part != "objects" or arch.reads_objects]
    _keys(path, data, [f"{part}_{what}" for part in parts for what in ("mean", "std")],
          where="normalization: ")
    found = {}
    for key, values in data.items():
        width = NORMALIZED[key.rsplit("_", 1)[0]]
        if not isinstance(values, list) or len(values) != width:
            raise CheckpointError(f"{path}: normalization.{key} is {shown(values)}, not a list "
                                  f"of {width} numbers")
        for index, value in enumerate(values):
            problem = number_problem(value, 0.0 if key.endswith("_std") else None)
            if problem or (key.endswith("_std") and value == 0):
                raise CheckpointError(f"{path}: normalization.{key}[{index}] "
                                      f"{problem or 'is 0, not above 0'}")
        found[key] = np.asarray(values, np.float32)
    return found


def _params(path: Path, shapes: dict[str, tuple[int, ...]]) -> dict[str, np.ndarray]:
    """params.npz: exactly the arrays the architecture has (`shapes`), each of its shape, of
    finite floats; each array's header is checked before its data is read."""
    def read(archive: zipfile.ZipFile) -> dict[str, np.ndarray]:
        stored = {info.filename.removesuffix(".npy"): info.filename
                  for info in archive.infolist()}
        found = key_problem(stored, shapes)
        if found:
            kind, name = found
            raise CheckpointError(f"{path}: {'lacks' if kind == 'missing' else 'holds'} "
                                  f"the array {shown(name)}, which the architecture "
                                  f"{'has' if kind == 'missing' else 'has not'}")
        return {name: _array(path, archive, stored[name], shapes[name]) for name in shapes}
    return _archive(path, MAX_PARAMS_BYTES, "not a readable baseline checkpoint", read)


def _archive(path: Path, limit: int, what: str, read):
    """`read(archive)` of the .npz file at `path`, a regular file of at most `limit` bytes;
    else a CheckpointError naming it and saying `what`."""
    problem = file_problem(path, limit)
    if problem:
        raise CheckpointError(f"{path}: {problem}; {what}")
    try:
        with zipfile.ZipFile(path) as archive:
            return read(archive)
    except (OSError, EOFError, ValueError, zipfile.BadZipFile, zlib.error, RuntimeError,
            NotImplementedError) as error:
        raise CheckpointError(f"{path}: {what} ({error_text(error)})") from None


def _header(archive: zipfile.ZipFile, member: str) -> tuple[tuple[int, ...], np.dtype]:
    """A .npy member's shape and dtype, from its header alone."""
    with archive.open(member) as stream:
        version = np.lib.format.read_magic(stream)
        if version not in ((1, 0), (2, 0)):
            raise ValueError(f"{member.removesuffix('.npy')}: a .npy file of version "
                             f"{version}")
        read_header = (np.lib.format.read_array_header_1_0 if version == (1, 0) else
                       np.lib.format.read_array_header_2_0)
        shape, _, dtype = read_header(stream)
    return shape, dtype


def _read(archive: zipfile.ZipFile, member: str) -> np.ndarray:
    with archive.open(member) as stream:
        return np.lib.format.read_array(stream, allow_pickle=False)


def _array(path: Path, archive: zipfile.ZipFile, member: str, shape: tuple[int, ...]
           ) -> np.ndarray:
    name = member.removesuffix(".npy")
    stored, dtype = _header(archive, member)
    if stored != shape:
        raise CheckpointError(f"{path}: {name} has the shape {stored}, but the architecture "
                              f"needs {shape}")
    if dtype.kind != "f":
        raise CheckpointError(f"{path}: {name} holds {dtype}, not floats")
    array = _read(archive, member)
    if not np.isfinite(array).all():
        raise CheckpointError(f"{path}: {name} holds values that are not finite (NaN or "
                              "infinite)")
    return array


def load_optimizer(folder: Path) -> dict[str, np.ndarray]:
    """optimizer.npz: Adam's step and moments, at most MAX_OPTIMIZER_BYTES of arrays (their
    headers are read before their data)."""
    return _archive(folder / "optimizer.npz", MAX_OPTIMIZER_BYTES, "cannot resume", _moments)


def _moments(archive: zipfile.ZipFile) -> dict[str, np.ndarray]:
    headers = {member: _header(archive, member) for member in archive.namelist()}
    size = sum(math.prod(shape) * dtype.itemsize for shape, dtype in headers.values())
    if size > MAX_OPTIMIZER_BYTES:
        raise ValueError(f"its arrays hold {size:,} bytes, more than the {MAX_OPTIMIZER_BYTES:,}"
                         " of an optimizer state")
    return {member.removesuffix(".npy"): _read(archive, member) for member in headers}


def _atomic(path: Path, write) -> None:
    partial = path.with_name(f".{path.name}.partial")
    with open(partial, "wb") as file:
        write(file)
        file.flush()
        os.fsync(file.fileno())
    partial.replace(path)
