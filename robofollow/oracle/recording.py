"""One trajectory prepared for scoring: the arrays every stage reads, and the physical events
the stages are judged on, each computed once per recording.

Every event is read from simulated physics, never from the commanded gripper value:

- a **hold** is both fingers of one arm on one movable body (the recorder's `grasped`) with
  the body between them (their measured gap, opening x `gripper_span`, at least its narrowest
  width less `grip_slack`: shut fingertips pressed on a body hold nothing), for
  `grasp_frames` frames in a row, the fingers having closed onto it (in the `grasp_window`
  frames before, they were `grasp_closing` wider apart: a body wedged against shut fingers
  prises them open instead); it ends (a **release**) when they no longer hold it;
- a **close** is the measured opening going from open (`open_threshold`, for `open_frames` in
  a row: not fingers prised open for an instant) to shut (`close_threshold`) while the arm
  holds nothing (fingers shut in free air); it goes for the body whose centre is within
  `reach_radius` (3-D) of the grasp centre, if any;
- a **push** is a body starting to move (`push_moved` from where it stood) while an arm's
  gripper, or the body that arm holds, touches it (or the grasp centre is within
  `push_contact_radius`, 3-D, in the `push_contact_frames` before);
- an **attempt** is what an arm went for: a hold's start, a close near a body, or a push.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from robofollow.compiler.planning.profile import ScoringProfile
from robofollow.compiler.scene.spec import Scene
from robofollow.compiler.scene.world import World
from robofollow.oracle import predicates as P
from robofollow.trajectory import ARMS, Trajectory, TrajectoryError, tilt

GRIPPERS = ("left_gripper", "right_gripper")  # contact names of the two grippers
AttemptKind = Literal["grasp", "close", "push"]
ATTEMPT_WORDS = {"grasp": "grasped", "close": "closed its fingers at", "push": "pushed"}


@dataclass(frozen=True, slots=True)
class Hold:
    """Both fingers of `arm` on `body` from frame `start`; `end` is the first frame it is no
    longer held (None: held to the last frame)."""

    arm: int
    body: int
    start: int
    end: int | None


@dataclass(frozen=True, slots=True)
class Attempt:
    """An arm going for a body at `frame`: grasping it, closing its fingers near it, or
    pushing it; `distance` is the grasp centre's distance to the body's centre (m, 3-D)."""

    arm: int
    body: int
    frame: int
    kind: AttemptKind
    distance: float

    def words(self, bodies: tuple[str, ...]) -> str:
        return f"{ATTEMPT_WORDS[self.kind]} {bodies[self.body]} at frame {self.frame}"


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
        self.opening = np.asarray(trajectory.gripper, dtype=float)  # (T, 2) measured
        self.half = np.array([scene.bodies[b].half_extents for b in self.bodies], dtype=float)
        fixture = np.array([scene.bodies[b].fixture for b in self.bodies], dtype=bool)
        self.movable = np.flatnonzero(~fixture)
        self.spheres = np.array([scene.bodies[b].kind == "sphere" for b in self.bodies])
        held = np.asarray(trajectory.grasped, dtype=int)
        narrowest = 2 * self.half[:, :2].min(axis=1)  # (B,) m
        gap = self.opening * profile.gripper_span  # (T, 2) m
        between = gap >= narrowest[np.maximum(held, 0)] - profile.grip_slack
        self.held = np.where((held >= 0) & ~fixture[np.maximum(held, 0)] & between, held, -1)
        self.last = len(trajectory) - 1
        self.memo: dict = {}  # per-recording results: events, settling, stage outcomes

    def index(self, body: str) -> int:
        return self.bodies.index(body)

    def cached(self, key: tuple, compute):
        """compute(), once per recording for each key."""
        if key not in self.memo:
            self.memo[key] = compute()
        return self.memo[key]

    # -- grasps and releases ---------------------------------------------------------------

    def holds(self, arm: int) -> tuple[Hold, ...]:
        """The arm's holds in time order."""
        return self.cached(("holds", arm), lambda: self._holds(arm))

    def _holds(self, arm: int) -> tuple[Hold, ...]:
        p, held = self.profile, self.held[:, arm]
        change = np.flatnonzero(np.diff(held)) + 1
        starts = np.concatenate(([0], change))
        ends = np.concatenate((change, [len(held)]))
        runs: list[list[int]] = []  # [body, start, end) with short gaps merged
        for start, end in zip(starts, ends, strict=True):
            body = int(held[start])
            if body < 0:
                continue
            if runs and runs[-1][0] == body and start - runs[-1][2] <= p.grasp_gap:
                runs[-1][2] = int(end)
            else:
                runs.append([body, int(start), int(end)])
        opening = self.opening[:, arm]
        return tuple(Hold(arm, body, start, None if end == len(held) else end)
                     for body, start, end in runs if end - start >= p.grasp_frames and
                     opening[max(0, start - p.grasp_window):start + 1].max()
                     >= opening[start] + p.grasp_closing)

    def holding(self, arm: int) -> np.ndarray:
        """(T,) the body the arm holds at each frame (merged holds), or -1."""
        def compute() -> np.ndarray:
            held = np.full(len(self.trajectory), -1)
            for hold in self.holds(arm):
                held[hold.start:hold.end] = hold.body
            return held
        return self.cached(("holding", arm), compute)

    def closes(self, arm: int) -> np.ndarray:
        """Frames where the arm's fingers shut in free air: the measured opening falls to the
        close threshold, having been open (for `open_frames` in a row) since the previous such
        fall, while it holds nothing."""
        def compute() -> np.ndarray:
            p, opening = self.profile, self.opening[:, arm]
            frames = P.falls(opening, p.close_threshold)
            opened = np.flatnonzero(P.holds_for(opening >= p.open_threshold, p.open_frames))
            since = np.searchsorted(opened, frames) > np.searchsorted(
                opened, np.concatenate(([-1], frames[:-1])), side="right")  # open in between
            return frames[since & (self.holding(arm)[frames] < 0)]
        return self.cached(("closes", arm), compute)

    # -- pushes ----------------------------------------------------------------------------

    def pushes(self) -> tuple[Attempt, ...]:
        """Every movable body that started moving from where it stood, while not held, with an
        arm at it: (arm, body, the first frame it had moved `push_moved`)."""
        return self.cached(("pushes",), self._pushes)

    def _pushes(self) -> tuple[Attempt, ...]:
        p = self.profile
        held = np.stack([self.holding(a) for a in range(2)], axis=1)  # (T, 2)
        names = self.trajectory.contact_names
        grippers = [names.index(g) for g in GRIPPERS]
        found = []
        for body in self.movable:
            ever_held = np.flatnonzero((held == body).any(axis=1))
            until = int(ever_held[0]) if len(ever_held) else len(held)
            moved = np.linalg.norm(self.xy[:until, body] - self.xy[0, body], axis=1)
            onset = P.first_true(moved >= p.push_moved)
            if onset is None:
                continue
            window = slice(max(0, onset - p.push_contact_frames), onset + 1)
            by = self._pusher(body, window, grippers, held)
            if by is not None:
                distance = float(np.linalg.norm(self.ee[onset, by] - self.positions[onset, body]))
                found.append(Attempt(by, int(body), onset, "push", distance))
        return tuple(sorted(found, key=lambda a: (a.frame, a.arm, a.body)))

    def _pusher(self, body: int, window: slice, grippers: list[int],
                held: np.ndarray) -> int | None:
        """The arm touching the body (with its gripper or the body it holds) in the window,
        else one whose grasp centre came within the push contact radius with this body the
        nearest to it (a body pushed along by another is not the arm's)."""
        contacts = self.trajectory.contacts[window]
        for arm in range(2):
            carried = held[window, arm]
            touched = contacts[:, grippers[arm], body].any() or any(
                contacts[i, c, body] for i, c in enumerate(carried) if c >= 0)
            if touched:
                return arm
        for frame in range(window.start, window.stop):  # the body nearest a grasp centre
            gaps = np.linalg.norm(self.positions[frame, self.movable][:, None] - self.ee[frame],
                                  axis=2)  # (movable, arm)
            for arm in np.argsort(gaps.min(axis=0)):
                nearest = int(np.argmin(gaps[:, arm]))
                if self.movable[nearest] == body and \
                        gaps[nearest, arm] <= self.profile.push_contact_radius:
                    return int(arm)
        return None

    # -- attempts --------------------------------------------------------------------------

    def attempts(self, arm: int) -> tuple[Attempt, ...]:
        """What the arm went for, in time order: grasps, closes near a body, pushes."""
        return self.cached(("attempts", arm), lambda: self._attempts(arm))

    def _attempts(self, arm: int) -> tuple[Attempt, ...]:
        found = [Attempt(arm, h.body, h.start, "grasp", self._gap(arm, h.body, h.start))
                 for h in self.holds(arm)]
        for frame in self.closes(arm):
            frame = int(frame)
            gaps = np.linalg.norm(self.positions[frame, self.movable] - self.ee[frame, arm],
                                  axis=1)
            nearest = int(np.argmin(gaps))
            if gaps[nearest] <= self.profile.reach_radius:
                found.append(Attempt(arm, int(self.movable[nearest]), frame, "close",
                                     float(gaps[nearest])))
        found += [a for a in self.pushes() if a.arm == arm]
        return tuple(sorted(found, key=lambda a: (a.frame, a.body)))

    def _gap(self, arm: int, body: int, frame: int) -> float:
        return float(np.linalg.norm(self.ee[frame, arm] - self.positions[frame, body]))

    def first_attempt(self, arm: int, after: int = 0,
                      kinds: tuple[AttemptKind, ...] = ("grasp", "close", "push"),
                      body: int | None = None) -> Attempt | None:
        """The arm's first attempt of those kinds at or after `after` (on `body`, if given)."""
        return next((a for a in self.attempts(arm) if a.frame >= after and a.kind in kinds
                     and (body is None or a.body == body)), None)

    # -- where bodies are ------------------------------------------------------------------

    def settled(self, body: int, after: int) -> int:
        """The first frame at or after `after` from which the body keeps within
        `settle_range` for `settle_frames` frames (the last frame if it never does)."""
        def compute() -> int:
            p = self.profile
            steady = P.steady(self.positions[after:, body], p.settle_frames, p.settle_range)
            hits = np.flatnonzero(steady)
            return after + int(hits[0]) if len(hits) else self.last
        return self.cached(("settled", body, after), compute)

    def heights_above_surface(self, body: int, frames: slice) -> np.ndarray:
        """(F,) how far the body's bottom is above what is under it over a range of frames
        (m): the top of the highest other body whose footprint overlaps its own and whose top
        is below its centre, else the table."""
        xy, z = self.xy[frames, body], self.z[frames, body]  # (F, 2), (F,)
        reach = self.half[:, :2] + self.half[body, :2]
        over = np.all(np.abs(self.xy[frames] - xy[:, None]) < reach, axis=2)
        tops = self.z[frames] + self.half[:, 2]  # (F, B)
        below = over & (tops <= z[:, None])
        below[:, body] = False
        surface = np.where(below, tops, -np.inf).max(axis=1)
        return self.bottom(body)[frames] - np.maximum(surface, self.scene.table_height)

    def support_of(self, body: int, frame: int) -> int | None:
        """The body directly under `body` at this frame, if it rests on one."""
        p = self.profile
        offset = np.linalg.norm(self.xy[frame] - self.xy[frame, body], axis=1)
        drop = self.z[frame, body] - self.z[frame]
        under = np.flatnonzero((offset <= p.support_xy) & (drop >= p.support_rise))
        return int(under[np.argmax(self.z[frame, under])]) if len(under) else None

    def tilt_deg(self, body: int) -> float:
        """How far the body has tipped over since the start (deg; 0 for spheres)."""
        if self.spheres[body]:
            return 0.0
        q = self.trajectory.quaternions
        return self.cached(("tilt", body),
                           lambda: float(np.degrees(tilt(q[0, body], q[-1, body]))))

    def still(self, arm: int, frames: int, radius: float) -> np.ndarray:
        """(T,) whether the arm's grasp centre moves within `radius` over the next `frames`
        frames from each frame."""
        return self.cached(("still", arm, frames, radius),
                           lambda: P.steady(self.ee[:, arm], frames, radius))

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
