"""A recorded episode as plain numpy arrays: what the oracle scores, wherever it was recorded.

One frame per control step (frame 0 is the settled start). `bodies` are the layout's bodies;
`contact_names` adds the table and the two grippers. Saved as a compressed .npz file.
"""

from __future__ import annotations

import json
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robofollow.errors import RoboFollowError, error_text
from robofollow.files import file_problem, size_text

ARMS = ("left", "right")
CONTACT_EXTRAS = ("table", "left_gripper", "right_gripper")
MAX_TRAJECTORY_BYTES = 1 << 30  # a trajectory's arrays unpacked (and so its file): scene 2's
#   124-step pick-up takes 97 KB (41 KB saved); a long episode of a large layout, a few MB


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
        """Read a saved trajectory; TrajectoryError says what is wrong with a bad file."""
        problem = npz_problem(Path(path), MAX_TRAJECTORY_BYTES)
        if problem:
            raise TrajectoryError(f"{path}: cannot read a trajectory: {problem}")
        try:
            with np.load(path, allow_pickle=False) as data:
                missing = [k for k in ("bodies", "meta", *_ARRAYS) if k not in data.files]
                if missing:
                    raise TrajectoryError(f"{path}: not a RoboFollow trajectory (missing "
                                          f"{', '.join(missing)})")
                trajectory = cls(bodies=tuple(str(b) for b in data["bodies"]),
                                 meta=json.loads(str(data["meta"])),
                                 **{name: data[name] for name in _ARRAYS})
        except (OSError, ValueError, MemoryError, zipfile.BadZipFile) as error:
            raise TrajectoryError(f"{path}: cannot read a trajectory ({error_text(error)})"
                                  ) from None
        trajectory.check(path)
        return trajectory

    def check(self, where: str | Path = "trajectory") -> None:
        """Raise TrajectoryError unless every array has one row per frame and the right
        shape for the bodies."""
        frames, bodies = len(self.time), len(self.bodies)
        shapes = {"state": (frames, 14), "action": (frames, 14), "positions": (frames, bodies, 3),
                  "quaternions": (frames, bodies, 4), "ee_positions": (frames, 2, 3),
                  "ee_quaternions": (frames, 2, 4), "grasped": (frames, 2)}
        for name, shape in shapes.items():
            if getattr(self, name).shape != shape:
                raise TrajectoryError(f"{where}: {name} has shape {getattr(self, name).shape}, "
                                      f"expected {shape} ({frames} frames, {bodies} bodies)")
        if frames == 0:
            raise TrajectoryError(f"{where}: the trajectory has no frames")


def npz_problem(path: Path, limit: int) -> str | None:
    """Why a .npz file is not handed to np.load: it is not a regular file of at most `limit`
    bytes (file_problem), not a zip archive, or its arrays unpack to more than `limit` (whole
    MiB); None when it may be. (An array's header may still claim more than its data: loading
    it then fails.)"""
    problem = file_problem(path, limit)
    if problem:
        return problem
    try:
        with zipfile.ZipFile(path) as archive:
            unpacked = sum(info.file_size for info in archive.infolist())
    except zipfile.BadZipFile:
        return "not a .npz file (not a zip archive)"
    except OSError as error:
        return f"cannot be read ({error.strerror or error})"
    return f"its arrays unpack to more than {size_text(limit)}" if unpacked > limit else None


_ARRAYS = ("movable", "time", "state", "action", "positions", "quaternions", "ee_positions",
           "ee_quaternions", "grasped", "contacts")


class TrajectoryError(RoboFollowError):
    """A trajectory file that cannot be read or does not hold a whole trajectory."""


def yaw(quaternion: np.ndarray) -> np.ndarray:
    """Rotation about z (rad) of (..., 4) quaternions (w, x, y, z): the heading of the body's
    x axis projected on the table."""
    w, x, y, z = np.moveaxis(np.asarray(quaternion), -1, 0)
    return np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def tilt(before: np.ndarray, after: np.ndarray) -> np.ndarray:
    """Angle (rad) between a body's up axis at two orientations, quaternions (..., 4)
    (w, x, y, z): how far it tipped over, whatever it turned about the vertical."""
    def up(quaternion: np.ndarray) -> np.ndarray:
        w, x, y, z = np.moveaxis(np.asarray(quaternion, dtype=float), -1, 0)
        return np.stack([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)], -1)

    cosine = np.sum(up(before) * up(after), axis=-1)
    return np.arccos(np.clip(cosine, -1.0, 1.0))
