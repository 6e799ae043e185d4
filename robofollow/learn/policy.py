"""A baseline checkpoint as a policy: NumPy inference, deterministic, no training stack needed.

Checkpoints load from a folder (`--policy runs/scene2-text/`) or, for the ones behind the
published results, by name (`--policy baseline:scene2-text`, shipped in robofollow/baselines).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from robofollow.errors import did_you_mean
from robofollow.learn import checkpoint
from robofollow.learn.demos import downsample
from robofollow.learn.model import forward, normalised_objects
from robofollow.learn.tokens import encode

SHIPPED = Path(__file__).resolve().parent.parent / "baselines"


class BaselinePolicy:
    """Predicts a chunk of joint targets from the cameras (or the objects observation), the
    joint state and (unless blind) the instruction; returns the first `execute` actions of
    it."""

    def __init__(self, ckpt: checkpoint.Checkpoint):
        self.ckpt = ckpt
        self.uses = frozenset({"state", "instruction",
                               "objects" if ckpt.arch.reads_objects else "images"})
        self._tokens: dict[str, np.ndarray] = {}

    def reset(self) -> None:
        """Nothing carries over between episodes."""

    def _shrunk(self, camera: str, image) -> np.ndarray:
        """The camera image at the trained size (rendered sizes are whole multiples of it)."""
        image = np.asarray(image)
        height, width = self.ckpt.arch.image_shape
        factor = image.shape[1] // width
        if factor < 1 or image.shape[:2] != (height * factor, width * factor):
            raise ValueError(f"{camera} image is {image.shape[1]}x{image.shape[0]}; the "
                             f"baseline reads {width}x{height} or a whole multiple of it")
        return downsample(image, factor)

    def act(self, observation: dict) -> np.ndarray:
        ckpt, arch = self.ckpt, self.ckpt.arch
        norm = ckpt.normalization
        images = {camera: self._shrunk(camera, observation["images"][camera])[None]
                  for camera in arch.cameras}
        state = ((np.asarray(observation["state"], np.float32) - norm["state_mean"])
                 / norm["state_std"])[None]
        text = observation.get("instruction", "")
        if text not in self._tokens:
            self._tokens[text] = encode(arch.kind, text, ckpt.vocab)[None]
        objects = (normalised_objects(observation["objects"], norm)[None]
                   if arch.reads_objects else None)
        chunk = forward(ckpt.params, arch, images, state, self._tokens[text],
                        objects=objects)[0]
        return (chunk * norm["action_std"] + norm["action_mean"])[: ckpt.execute]


def shipped_names() -> list[str]:
    return sorted(p.name for p in SHIPPED.iterdir() if checkpoint.is_checkpoint(p)) \
        if SHIPPED.is_dir() else []


def shipped_folder(spec: str) -> Path:
    """The folder of a shipped baseline named `baseline:NAME`; else the error, with the
    closest name."""
    name, shipped = spec[len(checkpoint.PREFIX):], shipped_names()
    if name not in shipped:
        hint = did_you_mean(name, shipped) or f"shipped: {', '.join(shipped) or 'none'}"
        raise checkpoint.CheckpointError(f"--policy {spec!r}: no shipped baseline {name!r}; "
                                         f"{hint}")
    return SHIPPED / name


def load_baseline(spec: str) -> BaselinePolicy:
    """A policy from `baseline:NAME` or a checkpoint folder."""
    folder = shipped_folder(spec) if spec.startswith(checkpoint.PREFIX) else Path(spec)
    return BaselinePolicy(checkpoint.load(folder))
