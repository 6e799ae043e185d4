"""Predicates over a recorded trajectory: gripper events, lifts, relations, stacking, bowls,
pushes, routes, yaw and the return home.

Pure numpy on plain arrays (frames first); thresholds arrive as arguments, from the scoring
profile. No MuJoCo: a trajectory recorded anywhere can be scored.
"""

from __future__ import annotations

import math

import numpy as np


def falls(signal: np.ndarray, threshold: float) -> np.ndarray:
    """Frames where a gripper signal closes: it falls from above `threshold` to it or below
    (frame 0 counts when the signal starts there)."""
    below = signal <= threshold
    return np.flatnonzero(below & np.concatenate(([True], ~below[:-1])))


def rises(signal: np.ndarray, threshold: float) -> np.ndarray:
    """Frames where a gripper signal opens: it rises from below `threshold` to it or above."""
    above = signal >= threshold
    return np.flatnonzero(above & np.concatenate(([False], ~above[:-1])))


def first(frames: np.ndarray, after: int = 0) -> int | None:
    """The first of the (sorted) frames at or after `after`."""
    index = int(np.searchsorted(frames, after))
    return int(frames[index]) if index < len(frames) else None


def first_true(mask: np.ndarray, after: int = 0) -> int | None:
    """The first frame at or after `after` where `mask` holds."""
    hits = np.flatnonzero(mask[after:])
    return after + int(hits[0]) if len(hits) else None


def nearest(points: np.ndarray, point: np.ndarray, candidates: np.ndarray) -> tuple[int, float]:
    """The candidate (index into `points`, (B, 2)) nearest to `point` in the plane, and its
    distance (m)."""
    distances = np.linalg.norm(points[candidates] - point, axis=1)
    best = int(np.argmin(distances))
    return int(candidates[best]), float(distances[best])


def in_cone(offset: np.ndarray, direction: tuple[float, float] | None, reach: float,
            cone_deg: float) -> np.ndarray:
    """(T,) whether planar offsets (T, 2) lie within `reach` (m) and, given a direction,
    within `cone_deg` of it (without one, any direction: 'next to')."""
    length = np.linalg.norm(offset, axis=-1)
    ok = (length > 1e-6) & (length <= reach)
    if direction is not None:
        along = offset @ np.asarray(direction, dtype=float)
        ok &= along >= length * math.cos(math.radians(cone_deg)) - 1e-12
    return ok


def resting_on(bottom: np.ndarray, surface: float | np.ndarray, tolerance: float) -> np.ndarray:
    """(T,) whether a body's bottom is within `tolerance` (m) of a surface's height."""
    return np.abs(bottom - surface) <= tolerance


def stacked(source: np.ndarray, target: np.ndarray, half_heights: float, xy: float,
            clearance: float) -> np.ndarray:
    """(T,) whether the source (T, 3) sits on the target (T, 3): centred within `xy` (m), and
    its centre at least the two half-heights less `clearance` above the target's."""
    offset = np.linalg.norm(source[:, :2] - target[:, :2], axis=1)
    return (offset <= xy) & (source[:, 2] - target[:, 2] >= half_heights - clearance)


def in_bowl(source: np.ndarray, bowl: np.ndarray, xy: float, height: float) -> np.ndarray:
    """(T,) whether the source (T, 3) is inside the bowl (T, 3): within `xy` (m) of its axis
    and at most `height` (m) above its centre."""
    offset = np.linalg.norm(source[:, :2] - bowl[:, :2], axis=1)
    return (offset <= xy) & (source[:, 2] <= bowl[:, 2] + height)


def progress(displacement: np.ndarray, direction: np.ndarray, cone_deg: float) -> np.ndarray:
    """(T,) how far planar displacements (T, 2) went along a unit direction, counted only
    within `cone_deg` of it (0 elsewhere)."""
    along = displacement @ direction
    length = np.linalg.norm(displacement, axis=1)
    inside = along >= length * math.cos(math.radians(cone_deg)) - 1e-12
    return np.where(inside, along, 0.0)


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


def over_footprint(path: np.ndarray, centre: np.ndarray, half: tuple[float, float]) -> np.ndarray:
    """(T,) whether a planar path (T, 2) is over a body's footprint (centre (T, 2), half
    extents in x and y)."""
    return np.all(np.abs(path - centre) <= np.asarray(half), axis=1)


def axis_error(angle: float, target: float) -> float:
    """Difference of two axis directions modulo 180 degrees (rad, 0 to pi/2)."""
    error = (angle - target) % math.pi
    return min(error, math.pi - error)


def within(points: np.ndarray, centre: np.ndarray, radius: float) -> np.ndarray:
    """(T,) whether points (T, 3) are within `radius` (m) of `centre`."""
    return np.linalg.norm(points - centre, axis=1) <= radius


def inside_box(points: np.ndarray, box) -> np.ndarray:
    """(T,) whether points (T, 3) are inside an axis-aligned box ((lo, hi) per axis, m)."""
    box = np.asarray(box, dtype=float)
    return np.all((points >= box[:, 0]) & (points <= box[:, 1]), axis=1)


def first_stay(mask: np.ndarray, after: int, frames: int) -> int | None:
    """The first frame at or after `after` that starts a run of `frames` consecutive frames
    where `mask` holds (or a run to the end, if fewer frames remain)."""
    n = len(mask)
    counts = np.concatenate(([0], np.cumsum(mask, dtype=int)))
    starts = np.arange(after, n)
    ends = np.minimum(starts + frames, n)
    hits = np.flatnonzero(counts[ends] - counts[starts] == ends - starts)
    return int(starts[hits[0]]) if len(hits) else None
