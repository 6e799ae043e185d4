"""The `objects` observation: what a perfect perception module would report at each step, read
from the simulation (ground truth, not estimated).

For every body of the layout, objects and fixtures alike, one row of FIELDS: present (1; 0 in
the padding rows), its shape kind one-hot, its size (full extents, m), its colour (RGB, 0-1),
its position (m, world frame) and its yaw (sine and cosine). Colours are those the layout
shows (a layout may repaint a body). Rows are sorted by their emitted values (x, then y, then
the other columns in order), so their order carries no identity: no name, id, task, layout or
seed is in it, and two bodies that look alike are interchangeable. A float32 array of
MAX_OBJECTS x len(FIELDS), padded with zero rows.

The yaw is the body's own, also where no camera could tell it (a sphere, an upright cylinder
or a bowl looks the same at every yaw; a cube repeats every 90 degrees): ground truth, not
what is visible."""

from __future__ import annotations

from typing import get_args

import numpy as np

from robofollow.compiler.scene.spec import BodyKind, Scene
from robofollow.errors import RoboFollowError
from robofollow.sim.simulation import Simulation
from robofollow.trajectory import Trajectory, yaw

KINDS = get_args(BodyKind)
FIELDS = ("present", *(f"is_{kind}" for kind in KINDS), "size_x", "size_y", "size_z",
          "red", "green", "blue", "x", "y", "z", "yaw_sin", "yaw_cos")
MAX_OBJECTS = 12  # rows: the largest layout holds 7 bodies
SHAPE = (MAX_OBJECTS, len(FIELDS))
FLAT = MAX_OBJECTS * len(FIELDS)  # values of the observation flattened row by row (datasets)


def _looks(scene: Scene, layout: str, bodies: list[str] | tuple[str, ...]) -> np.ndarray:
    """Each body's fixed columns: its kind one-hot, size and colour in the layout."""
    if len(bodies) > MAX_OBJECTS:
        raise RoboFollowError(f"a layout of {len(bodies)} bodies: the objects observation "
                              f"holds at most {MAX_OBJECTS}")
    shown = scene.bodies_in(layout)
    return np.array([(*(float(shown[b].kind == kind) for kind in KINDS),
                      *(2 * np.asarray(shown[b].half_extents)), *shown[b].rgb)
                     for b in bodies], dtype=np.float64)


def _rows(looks: np.ndarray, positions: np.ndarray, quaternions: np.ndarray) -> np.ndarray:
    """One frame's observation from its bodies' looks, positions (B, 3) and quaternions."""
    angle = yaw(quaternions)
    rows = np.concatenate([np.ones((len(looks), 1)), looks, positions, np.sin(angle)[:, None],
                           np.cos(angle)[:, None]], axis=1).astype(np.float32)
    x, y = FIELDS.index("x"), FIELDS.index("y")
    keys = [rows[:, column] for column in reversed(range(rows.shape[1]))
            if column not in (x, y)]  # ties in x and y (a cube in a bowl) broken by the rest
    found = np.zeros(SHAPE, dtype=np.float32)
    found[:len(rows)] = rows[np.lexsort((*keys, rows[:, y], rows[:, x]))]
    return found


def observe_objects(sim: Simulation) -> np.ndarray:
    """The objects observation of a Simulation now."""
    return _rows(_looks(sim.scene, sim.layout, sim.bodies), sim.positions(), sim.quaternions())


def objects_over(trajectory: Trajectory, scene: Scene, layout: str) -> np.ndarray:
    """The objects observation at every frame of a recording of `layout`: (T, *SHAPE)."""
    looks = _looks(scene, layout, trajectory.bodies)
    return np.stack([_rows(looks, positions, quaternions) for positions, quaternions
                     in zip(trajectory.positions, trajectory.quaternions, strict=True)])
