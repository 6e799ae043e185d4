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
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from robofollow.errors import RoboFollowError
from robofollow.files import write_json_atomic
from robofollow.learn.model import Architecture

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
    return (Path(path) / "policy.json").is_file()


def save(folder: Path, checkpoint: Checkpoint, optimizer: dict[str, np.ndarray] | None = None
         ) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    _atomic(folder / "params.npz", lambda f: np.savez(f, **checkpoint.params))
    if optimizer is not None:
        _atomic(folder / "optimizer.npz", lambda f: np.savez(f, **optimizer))
    write_json_atomic(folder / "policy.json", checkpoint.meta())


def load(folder: Path) -> Checkpoint:
    try:
        meta = json.loads((folder / "policy.json").read_text())
        if meta.get("format") != FORMAT:
            raise CheckpointError(f"{folder}/policy.json: format {meta.get('format')!r}, "
                                  f"expected {FORMAT!r}")
        with np.load(folder / "params.npz") as data:
            params = {key: data[key] for key in data.files}
        return Checkpoint(Architecture.from_dict(meta["architecture"]), meta["vocab"],
                          {k: np.asarray(v, np.float32) for k, v in meta["normalization"]
                           .items()}, meta["execute"], params,
                          meta["training"])
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise CheckpointError(f"{folder}: not a readable baseline checkpoint "
                              f"({type(error).__name__}: {error})") from None


def load_optimizer(folder: Path) -> dict[str, np.ndarray]:
    try:
        with np.load(folder / "optimizer.npz") as data:
            return {key: data[key] for key in data.files}
    except (OSError, ValueError) as error:
        raise CheckpointError(f"{folder}/optimizer.npz: cannot resume ({error})") from None


def _atomic(path: Path, write) -> None:
    partial = path.with_name(f".{path.name}.partial")
    with open(partial, "wb") as file:
        write(file)
        file.flush()
        os.fsync(file.fileno())
    partial.replace(path)
