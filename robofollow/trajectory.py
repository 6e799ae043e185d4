"""A recorded episode as plain numpy arrays: what the oracle scores, wherever it was recorded.

One frame per control step (frame 0 is the settled start). `bodies` are the layout's bodies;
`contact_names` adds the table and the two grippers. Saved as a compressed .npz file.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

ARMS = ("left", "right")
CONTACT_EXTRAS = ("table", "left_gripper", "right_gripper")


@dataclass
class Trajectory:
    bodies: tuple[str, ...]
    movable: np.ndarray  # (B,) bool
    time: np.ndarray  # (T,) s
    state: np.ndarray  # (T, 14) measured joints, grippers normalised (1 open, 0 closed)
    action: np.ndarray  # (T, 14) joint target in force when the frame was taken
    positions: np.ndarray  # (T, B, 3) body centres (m)
    quaternions: np.ndarray  # (T, B, 4) body orientations (w, x, y, z)
    ee_positions: np.ndarray  # (T, 2, 3) grasp centres of [left, right] (m)
    ee_quaternions: np.ndarray  # (T, 2, 4)
    grasped: np.ndarray  # (T, 2) index of the body each arm holds (both fingers touch), or -1
    contacts: np.ndarray  # (T, K, K) bool, K = B + 3 (contact_names)
    meta: dict = field(default_factory=dict)

    @property
    def contact_names(self) -> tuple[str, ...]:
        return self.bodies + CONTACT_EXTRAS

    @property
    def gripper(self) -> np.ndarray:
        """(T, 2) normalised gripper opening of [left, right]."""
        return self.state[:, [6, 13]]

    def __len__(self) -> int:
        return len(self.time)

    def index(self, body: str) -> int:
        return self.bodies.index(body)

    def save(self, path: str | Path) -> None:
        arrays = {name: getattr(self, name) for name in _ARRAYS}
        np.savez_compressed(path, bodies=np.array(self.bodies), meta=json.dumps(self.meta),
                            **arrays)

    @classmethod
    def load(cls, path: str | Path) -> "Trajectory":
        with np.load(path, allow_pickle=False) as data:
            return cls(bodies=tuple(str(b) for b in data["bodies"]),
                       meta=json.loads(str(data["meta"])),
                       **{name: data[name] for name in _ARRAYS})


_ARRAYS = ("movable", "time", "state", "action", "positions", "quaternions", "ee_positions",
           "ee_quaternions", "grasped", "contacts")


def yaw(quaternion: np.ndarray) -> np.ndarray:
    """Rotation about z (rad) of (..., 4) quaternions (w, x, y, z): the heading of the body's
    x axis projected on the table."""
    w, x, y, z = np.moveaxis(np.asarray(quaternion), -1, 0)
    return np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
