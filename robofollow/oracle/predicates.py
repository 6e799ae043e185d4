"""Predicates over a recorded trajectory: signal events, stillness, relations, pushes, routes
and footprints.

Pure numpy on plain arrays (frames first); thresholds arrive as arguments, from the scoring
profile. No MuJoCo: a trajectory recorded anywhere can be scored.
"""

from __future__ import annotations

import math

import numpy as np


def falls(signal: np.ndarray, threshold: float) -> np.ndarray:
    """Frames where a signal falls from above `threshold` to it or below (frame 0 counts when
    the signal starts there)."""
    below = signal <= threshold
    return np.flatnonzero(below & np.concatenate(([True], ~below[:-1])))


def first_true(mask: np.ndarray, after: int = 0) -> int | None:
    """The first frame at or after `after` where `mask` holds."""
    hits = np.flatnonzero(mask[after:])
    return after + int(hits[0]) if len(hits) else None


def holds_for(mask: np.ndarray, frames: int) -> np.ndarray:
    """(T,) whether `mask` holds on each of the `frames` frames from each frame on (fewer at
    the end: to the last frame)."""
    n = len(mask)
    counts = np.concatenate(([0], np.cumsum(mask, dtype=int)))
    starts = np.arange(n)
    ends = np.minimum(starts + frames, n)
    return counts[ends] - counts[starts] == ends - starts


def steady(points: np.ndarray, frames: int, radius: float) -> np.ndarray:
    """(T,) whether points (T, D) stay within `radius` of where they are at each frame over
    the next `frames` frames (fewer at the end)."""
    if len(points) == 0:
        return np.zeros(0, dtype=bool)
    padded = np.concatenate([points, np.repeat(points[-1:], frames - 1, axis=0)])
    windows = np.lib.stride_tricks.sliding_window_view(padded, frames, axis=0)  # (T, D, F)
    offsets = windows - points[:, :, None]
    return np.einsum("tdf,tdf->tf", offsets, offsets).max(axis=1) <= radius * radius


def in_cone(offset: np.ndarray, direction: tuple[float, float], cone_deg: float) -> np.ndarray:
    """(...) whether planar offsets (..., 2) point within `cone_deg` of a direction."""
    length = np.linalg.norm(offset, axis=-1)
    along = offset @ np.asarray(direction, dtype=float)
    return (length > 1e-6) & (along >= length * math.cos(math.radians(cone_deg)) - 1e-12)


def progress(displacement: np.ndarray, direction: np.ndarray, cone_deg: float) -> np.ndarray:
    """(T,) how far planar displacements (T, 2) went along a unit direction, counted only
    within `cone_deg` of it (0 elsewhere)."""
    along = displacement @ direction
    return np.where(in_cone(displacement, direction, cone_deg), along, 0.0)


def crossings(path: np.ndarray, x: float, near: float) -> tuple[np.ndarray, np.ndarray]:
    """Where a planar path (T, 2) comes within `near` (m) of the line at `x`, or crosses it
    between two frames: (frames, the path's y there, interpolated at crossings)."""
    near_line = np.abs(path[:, 0] - x) < near
    close = np.flatnonzero(near_line)
    side = np.sign(path[:, 0] - x)
    between = np.flatnonzero((side[:-1] * side[1:] < 0) & ~near_line[:-1] & ~near_line[1:])
    a, b = path[between], path[between + 1]
    t = (x - a[:, 0]) / (b[:, 0] - a[:, 0])
    frames = np.concatenate((close, between))
    ys = np.concatenate((path[close, 1], a[:, 1] + t * (b[:, 1] - a[:, 1])))
    order = np.argsort(frames, kind="stable")
    return frames[order], ys[order]


def over_footprint(path: np.ndarray, centre: np.ndarray, half: np.ndarray) -> np.ndarray:
    """(T,) whether points of a planar path (T, 2) lie over a footprint (centre (T, 2), half
    extents (2,) or (T, 2))."""
    return np.all(np.abs(path - centre) <= half, axis=-1)


def axis_error(angle: float, target: float) -> float:
    """Difference of two axis directions modulo 180 degrees (rad, 0 to pi/2)."""
    error = (angle - target) % math.pi
    return min(error, math.pi - error)


def inside_box(points: np.ndarray, box) -> np.ndarray:
    """(T,) whether points (T, 3) are inside an axis-aligned box ((lo, hi) per axis, m)."""
    box = np.asarray(box, dtype=float)
    return np.all((points >= box[:, 0]) & (points <= box[:, 1]), axis=1)
