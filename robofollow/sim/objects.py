"""The `objects` observation: what a perfect perception module would report at each step, read
from the simulation (ground truth, not estimated).

For every body of the layout, objects and fixtures alike, one row of FIELDS: present (1; 0 in
the padding rows), its shape kind one-hot, its size (full extents, m), its colour (RGB, 0-1),
its position (m, world frame) and its yaw (sine and cosine). Rows are sorted by position (x,
then y), so their order carries no identity: no name, id, task, layout or seed is in it, and
two bodies that look alike are interchangeable. A float32 array of MAX_OBJECTS x len(FIELDS),
padded with zero rows."""

from __future__ import annotations

from typing import get_args

import numpy as np

from robofollow.compiler.spec import BodyKind, Scene
from robofollow.errors import RoboFollowError
from robofollow.sim.simulation import Simulation
from robofollow.trajectory import Trajectory, yaw

KINDS = get_args(BodyKind)
FIELDS = ("present", *(f"is_{kind}" for kind in KINDS), "size_x", "size_y", "size_z",
          "red", "green", "blue", "x", "y", "z", "yaw_sin", "yaw_cos")
MAX_OBJECTS = 12  # rows: the largest layout holds 7 bodies
SHAPE = (MAX_OBJECTS, len(FIELDS))
FLAT = MAX_OBJECTS * len(FIELDS)  # values of the observation flattened row by row (datasets)


def _looks(scene: Scene, bodies: list[str] | tuple[str, ...]) -> np.ndarray:
    """Each body's fixed columns: its kind one-hot, size and colour."""
    if len(bodies) > MAX_OBJECTS:
        raise RoboFollowError(f"a layout of {len(bodies)} bodies: the objects observation "
                              f"holds at most {MAX_OBJECTS}")
    return np.array([(*(float(scene.bodies[b].kind == kind) for kind in KINDS),
                      *(2 * np.asarray(scene.bodies[b].half_extents)), *scene.bodies[b].rgb)
                     for b in bodies], dtype=np.float64)


def _rows(looks: np.ndarray, positions: np.ndarray, quaternions: np.ndarray) -> np.ndarray:
    """One frame's observation from its bodies' looks, positions (B, 3) and quaternions."""
    angle = yaw(quaternions)
    found = np.zeros(SHAPE, dtype=np.float32)
    order = np.lexsort((positions[:, 1], positions[:, 0]))  # by x, then y: no identity
    count = len(order)
    found[:count, 0] = 1.0
    found[:count, 1:] = np.concatenate(
        [looks[order], positions[order], np.sin(angle[order])[:, None],
         np.cos(angle[order])[:, None]], axis=1)
    return found


def observe_objects(sim: Simulation) -> np.ndarray:
    """The objects observation of a Simulation now."""
    return _rows(_looks(sim.scene, sim.bodies), sim.positions(), sim.quaternions())


def objects_over(trajectory: Trajectory, scene: Scene) -> np.ndarray:
    """The objects observation at every frame of a recording: (T, *SHAPE)."""
    looks = _looks(scene, trajectory.bodies)
    return np.stack([_rows(looks, positions, quaternions) for positions, quaternions
                     in zip(trajectory.positions, trajectory.quaternions, strict=True)])
