"""One trajectory prepared for scoring: the arrays every stage reads, and gripper events.

Gripper events read the *commanded* opening (the action), not the measured one: the fingers
stop at an object's width, so the measured opening of a firm grasp stays well above any close
threshold, while the command says what the policy meant to do.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robofollow.compiler.profile import ScoringProfile
from robofollow.compiler.spec import Scene
from robofollow.compiler.world import World
from robofollow.oracle import predicates as P
from robofollow.trajectory import ARMS, Trajectory, TrajectoryError

GRIPPER_COLUMNS = (6, 13)  # the gripper entries of the 14-D action, [left, right]


@dataclass(frozen=True, slots=True)
class Grasp:
    """A close of one arm's gripper near an object."""

    frame: int
    body: int  # the nearest graspable body (index into the trajectory's bodies)
    distance: float  # m, gripper to body in the plane


class Recording:
    def __init__(self, trajectory: Trajectory, scene: Scene, profile: ScoringProfile):
        unknown = [b for b in trajectory.bodies if b not in scene.bodies]
        if unknown or trajectory.meta.get("layout") not in scene.layouts:
            raise TrajectoryError(f"the trajectory does not belong to {scene.id}: "
                                  + (f"unknown bodies {', '.join(unknown)}" if unknown else
                                     f"layout {trajectory.meta.get('layout')!r} is not one of "
                                     f"its layouts"))
        self.trajectory, self.scene, self.profile = trajectory, scene, profile
        self.bodies = trajectory.bodies
        self.positions = np.asarray(trajectory.positions, dtype=float)  # (T, B, 3)
        self.xy = self.positions[:, :, :2]
        self.z = self.positions[:, :, 2]
        self.ee = np.asarray(trajectory.ee_positions, dtype=float)  # (T, 2, 3)
        self.command = np.asarray(trajectory.action, dtype=float)[:, GRIPPER_COLUMNS]
        self.half = np.array([scene.bodies[b].half_extents for b in self.bodies], dtype=float)
        self.graspable = np.flatnonzero([not scene.bodies[b].fixture for b in self.bodies])
        self.last = len(trajectory) - 1
        self.memo: dict = {}  # per-recording results: events, grasps, supports, stage outcomes

    def index(self, body: str) -> int:
        return self.bodies.index(body)

    def cached(self, key: tuple, compute):
        """compute(), once per recording for each key."""
        if key not in self.memo:
            self.memo[key] = compute()
        return self.memo[key]

    def closes(self, arm: int, threshold: float | None = None) -> np.ndarray:
        """Frames where the arm's gripper closes (falls to the threshold or below)."""
        threshold = self.profile.close_threshold if threshold is None else threshold
        return self.cached(("close", arm, threshold),
                            lambda: P.falls(self.command[:, arm], threshold))

    def opens(self, arm: int) -> np.ndarray:
        """Frames where the arm's gripper opens (rises to the open threshold or above)."""
        return self.cached(("open", arm),
                            lambda: P.rises(self.command[:, arm], self.profile.open_threshold))

    def grasps(self, arm: int) -> list[Grasp]:
        """The arm's grasp attempts: closes with a graspable body within the grasp radius
        (closes in free air are not attempts). The body is the nearest one in the plane; in a
        stack (bodies within `support_xy` of it in the plane), the one nearest the gripper in
        height."""
        return self.cached(("grasps", arm), lambda: self._attempts(arm))

    def _attempts(self, arm: int) -> list[Grasp]:
        attempts = []
        for frame in self.closes(arm):
            frame = int(frame)
            ee = self.ee[frame, arm]
            body, distance = P.nearest(self.xy[frame], ee[:2], self.graspable)
            if distance < self.profile.grasp_radius:
                attempts.append(Grasp(frame, self._in_stack(body, frame, ee[2]), distance))
        return attempts

    def _in_stack(self, body: int, frame: int, height: float) -> int:
        """Of the bodies stacked with `body` (itself included), the one nearest `height`."""
        offset = np.linalg.norm(self.xy[frame, self.graspable] - self.xy[frame, body], axis=1)
        stack = self.graspable[offset <= self.profile.support_xy]
        return int(stack[np.argmin(np.abs(self.z[frame, stack] - height))])

    def support_of(self, body: int, frame: int) -> int | None:
        """The body directly under `body` at this frame, if it rests on one."""
        return self.cached(("support", body, frame), lambda: self._support_of(body, frame))

    def _support_of(self, body: int, frame: int) -> int | None:
        p = self.profile
        offset = np.linalg.norm(self.xy[frame] - self.xy[frame, body], axis=1)
        drop = self.z[frame, body] - self.z[frame]
        under = np.flatnonzero((offset <= p.support_xy) & (drop >= p.support_rise))
        return int(under[np.argmax(self.z[frame, under])]) if len(under) else None

    def first_grasp(self, arm: int, after: int = 0) -> Grasp | None:
        return next((g for g in self.grasps(arm) if g.frame >= after), None)

    def rise(self, body: int, since: int) -> np.ndarray:
        """(T,) height of a body above where it was at frame `since` (m)."""
        return self.z[:, body] - self.z[since, body]

    def bottom(self, body: int) -> np.ndarray:
        return self.z[:, body] - self.half[body, 2]

    def top(self, body: int) -> np.ndarray:
        return self.z[:, body] + self.half[body, 2]

    def world(self, frame: int) -> World:
        positions = {b: tuple(p) for b, p in zip(self.bodies, self.positions[frame], strict=True)}
        return World(self.scene, self.trajectory.meta["layout"], positions=positions)


def arm_index(arm: str) -> int:
    return ARMS.index(arm)
