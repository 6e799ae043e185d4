"""The baselines' network, written once for two array libraries: NumPy runs a checkpoint as a
policy (no training stack needed), JAX trains it (`robofollow.learn.train`).

    images (per camera) -> 3 convolutions -> FiLM by the instruction -> spatial softmax + mean
    instruction tokens -> embeddings + one transformer block -> masked mean      (text, form)
    [image features, joint state, instruction] -> MLP -> a chunk of CHUNK x 14 joint targets

`blind` is the same network without the instruction: no token encoder and no FiLM.
`objects-text` and `objects-form` read the objects observation instead of images (perception
removed): each body's row -> a 2-layer MLP -> FiLM by the instruction; then the instruction
attends over the bodies (one query, masked softmax) beside their masked mean.
Parameters are a flat dict of float32 arrays; everything is normalised (images to [-0.5, 0.5],
state and actions by the dataset's mean and standard deviation).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from robofollow.learn.options import reads_objects
from robofollow.learn.tokens import MAX_TOKENS
from robofollow.sim import CHUNK
from robofollow.sim.objects import FIELDS

ACTION_WIDTH = 14
OBJECT_FIELDS = len(FIELDS)


@dataclass(frozen=True)
class Architecture:
    kind: str  # text | blind | form | objects-text | objects-form
    cameras: tuple[str, ...]
    image_shape: tuple[int, int]  # (height, width) after shrinking
    vocab_size: int
    chunk: int = CHUNK
    channels: tuple[int, ...] = (32, 64, 64)
    kernels: tuple[int, ...] = (5, 3, 3)
    strides: tuple[int, ...] = (2, 2, 1)
    embed: int = 64
    hidden: int = 512

    @property
    def reads_instruction(self) -> bool:
        return self.kind != "blind"

    @property
    def reads_objects(self) -> bool:
        """The objects observation instead of camera images."""
        return reads_objects(self.kind)

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> Architecture:
        return cls(**{key: tuple(value) if isinstance(value, list) else value
                      for key, value in data.items()})


def normalised_objects(objects: np.ndarray, normalization: dict) -> np.ndarray:
    """The objects observation [..., rows, fields] standardised by the dataset's field means
    and deviations (over the bodies present), its `present` column kept and padding rows 0."""
    objects = np.asarray(objects, np.float32)
    present = objects[..., :1]
    scaled = (objects - normalization["objects_mean"]) / normalization["objects_std"]
    return np.concatenate([present, scaled[..., 1:] * present], axis=-1)


def init(arch: Architecture, seed: int) -> dict[str, np.ndarray]:
    """Fresh parameters (He-normal weights, zero biases) drawn from `seed`."""
    rng = np.random.default_rng(seed)
    params: dict[str, np.ndarray] = {}

    def dense(name: str, fan_in: int, fan_out: int, scale: float = 1.0) -> None:
        params[f"{name}.w"] = (rng.standard_normal((fan_in, fan_out)) * scale
                               * math.sqrt(2.0 / fan_in)).astype(np.float32)
        params[f"{name}.b"] = np.zeros(fan_out, np.float32)

    features = 0
    for camera in arch.cameras:
        fan_in = 3
        for layer, (width, kernel) in enumerate(zip(arch.channels, arch.kernels, strict=True)):
            shape = (kernel, kernel, fan_in, width)
            params[f"{camera}.conv{layer}.w"] = (rng.standard_normal(shape) * math.sqrt(
                2.0 / (kernel * kernel * fan_in))).astype(np.float32)
            params[f"{camera}.conv{layer}.b"] = np.zeros(width, np.float32)
            fan_in = width
        if arch.reads_instruction:
            dense(f"{camera}.film", arch.embed, 2 * fan_in, scale=0.1)
        features += 3 * fan_in
    if arch.reads_objects:
        d = arch.embed
        dense("objects.in", OBJECT_FIELDS, d)
        dense("objects.hidden", d, d)
        dense("objects.film", d, 2 * d, scale=0.1)
        for name in ("query", "key", "value"):
            dense(f"objects.{name}", d, d, scale=0.5)
        features += 2 * d
    if arch.reads_instruction:
        d = arch.embed
        params["tokens.embed"] = (rng.standard_normal((arch.vocab_size, d)) * 0.1).astype(
            np.float32)
        params["tokens.position"] = (rng.standard_normal((MAX_TOKENS, d)) * 0.1).astype(np.float32)
        for name in ("query", "key", "value", "mix"):
            dense(f"tokens.{name}", d, d, scale=0.5)
        dense("tokens.up", d, 2 * d)
        dense("tokens.down", 2 * d, d, scale=0.5)
        features += d
    dense("trunk0", features + ACTION_WIDTH, arch.hidden)
    dense("trunk1", arch.hidden, arch.hidden)
    dense("head", arch.hidden, arch.chunk * ACTION_WIDTH, scale=0.1)
    return params


def numpy_conv(x: np.ndarray, w: np.ndarray, stride: int) -> np.ndarray:
    """A 'VALID' convolution of [B, H, W, C] by [k, k, C, D]."""
    k = w.shape[0]
    windows = sliding_window_view(x, (k, k), axis=(1, 2))[:, ::stride, ::stride]
    return np.einsum("bhwcij,ijcd->bhwd", windows, w, optimize=True)


def forward(params: dict, arch: Architecture, images: dict, state, tokens, xp=np,
            conv=numpy_conv, objects=None):
    """Normalised action chunks [B, chunk, 14] from uint8 images {camera: [B, H, W, 3]},
    normalised state [B, 14], token ids [B, L] (ignored by `blind`) and, for the objects
    kinds, the objects observation [B, rows, fields]."""
    def dense(name, x):
        return x @ params[f"{name}.w"] + params[f"{name}.b"]

    text = _encode_tokens(params, arch, tokens, xp, dense) if arch.reads_instruction else None
    parts = []
    for camera in arch.cameras:
        x = xp.asarray(images[camera], dtype=xp.float32) / 255.0 - 0.5
        last = len(arch.channels) - 1
        for layer, stride in enumerate(arch.strides):
            x = conv(x, params[f"{camera}.conv{layer}.w"], stride) \
                + params[f"{camera}.conv{layer}.b"]
            if layer == last and text is not None:
                scale, shift = xp.split(dense(f"{camera}.film", text), 2, axis=-1)
                x = x * (1.0 + scale[:, None, None, :]) + shift[:, None, None, :]
            x = xp.maximum(x, 0.0)
        parts.append(_spatial_features(x, xp))
    if arch.reads_objects:
        parts.append(_object_features(params, arch, objects, text, xp, dense))
    if text is not None:
        parts.append(text)
    parts.append(xp.asarray(state, dtype=xp.float32))
    x = xp.concatenate(parts, axis=-1)
    x = xp.maximum(dense("trunk0", x), 0.0)
    x = xp.maximum(dense("trunk1", x), 0.0)
    return dense("head", x).reshape(x.shape[0], arch.chunk, ACTION_WIDTH)


def _object_features(params, arch, objects, text, xp, dense):
    """The bodies encoded row by row and modulated by the instruction; then what the
    instruction attends to among them, and their mean ([B, 2 * embed])."""
    objects = xp.asarray(objects, dtype=xp.float32)
    mask = objects[..., 0]  # the `present` column
    h = xp.maximum(dense("objects.in", objects), 0.0)
    h = xp.maximum(dense("objects.hidden", h), 0.0)
    scale, shift = xp.split(dense("objects.film", text), 2, axis=-1)
    h = h * (1.0 + scale[:, None, :]) + shift[:, None, :]
    query = dense("objects.query", text)  # [B, d]
    logits = xp.einsum("bd,brd->br", query, dense("objects.key", h)) / math.sqrt(arch.embed) \
        + (mask - 1.0) * 1e9
    weights = xp.exp(logits - logits.max(axis=-1, keepdims=True)) * mask
    weights = weights / xp.maximum(weights.sum(axis=-1, keepdims=True), 1e-9)
    attended = xp.einsum("br,brd->bd", weights, dense("objects.value", h))
    mean = (h * mask[..., None]).sum(axis=1) / xp.maximum(mask.sum(axis=1, keepdims=True), 1.0)
    return xp.concatenate([attended, mean], axis=-1)


def _spatial_features(x, xp):
    """Per channel: the softmax-weighted mean image position (x, y in [-1, 1]) and the mean
    activation."""
    batch, height, width, channels = x.shape
    flat = x.reshape(batch, height * width, channels)
    weights = xp.exp(flat - flat.max(axis=1, keepdims=True))
    weights = weights / weights.sum(axis=1, keepdims=True)
    ys, xs = np.meshgrid(np.linspace(-1, 1, height), np.linspace(-1, 1, width), indexing="ij")
    grid = np.stack([xs.reshape(-1), ys.reshape(-1)], axis=-1).astype(np.float32)  # [HW, 2]
    points = xp.einsum("bnc,nk->bck", weights, grid).reshape(batch, 2 * channels)
    return xp.concatenate([points, flat.mean(axis=1)], axis=-1)


def _encode_tokens(params, arch, tokens, xp, dense):
    tokens = xp.asarray(tokens)
    mask = (tokens != 0).astype(xp.float32)  # [B, L]
    x = xp.take(params["tokens.embed"], tokens, axis=0) \
        + params["tokens.position"][: tokens.shape[1]]
    h = _layer_norm(x, xp)
    q, k, v = (dense(f"tokens.{name}", h) for name in ("query", "key", "value"))
    logits = xp.einsum("bid,bjd->bij", q, k) / math.sqrt(arch.embed) \
        + (mask[:, None, :] - 1.0) * 1e9
    attention = xp.exp(logits - logits.max(axis=-1, keepdims=True))
    attention = attention / attention.sum(axis=-1, keepdims=True)
    x = x + dense("tokens.mix", xp.einsum("bij,bjd->bid", attention, v))
    x = x + dense("tokens.down", xp.maximum(dense("tokens.up", _layer_norm(x, xp)), 0.0))
    count = xp.maximum(mask.sum(axis=1, keepdims=True), 1.0)
    return (x * mask[..., None]).sum(axis=1) / count


def _layer_norm(x, xp):
    mean = x.mean(axis=-1, keepdims=True)
    variance = ((x - mean) ** 2).mean(axis=-1, keepdims=True)
    return (x - mean) / xp.sqrt(variance + 1e-5)
