"""What physically happened, in words: per arm, what it went for (grasped, closed its
fingers at, pushed), how far it lifted and carried what it held and where it let go; then
where every moved object ended (on, in or beside a body, held, off the table, knocked over).
Read from the same events the stages are judged on, so it never contradicts them."""

from __future__ import annotations

import numpy as np

from robofollow.compiler.scene.world import DIRECTIONS
from robofollow.oracle import predicates as P
from robofollow.oracle.recording import Attempt, Recording
from robofollow.trajectory import ARMS

NOTHING_MOVED = "nothing moved"  # what the arms did, where they went for no object and none moved
TOUCHED_NOTHING = "the arms moved but touched nothing"  # ... though a gripper left its start
SIDES = {"left_of": "left of", "right_of": "right of", "behind": "behind",
         "in_front_of": "in front of"}
HEADINGS = {"left_of": "to the left", "right_of": "to the right", "behind": "away",
            "in_front_of": "towards the robot"}


def describe_actions(rec: Recording) -> str:
    """One clause per thing an arm went for, then one per object that ended elsewhere than
    it started (but those still held, said already); when neither, 'nothing moved' or, where
    a gripper left its start (arms_moved), 'the arms moved but touched nothing'."""
    clauses = [f"the {ARMS[a.arm]} arm {_did(rec, a)}"
               for a in sorted(rec.attempts(0) + rec.attempts(1), key=lambda a: a.frame)]
    held = {rec.holding(arm)[-1] for arm in range(2)}
    clauses += [_ended(rec, body) for body in rec.movable
                if body not in held and _moved(rec, body)]
    if clauses:
        return "; ".join(clauses)
    return TOUCHED_NOTHING if arms_moved(rec) else NOTHING_MOVED


def arms_moved(rec: Recording) -> bool:
    """Whether a gripper went further from where it started than the profile's still radius."""
    travel = np.linalg.norm(rec.ee - rec.ee[:1], axis=-1)  # (T, 2)
    return bool(travel.max(initial=0.0) > rec.profile.still_radius)


def _did(rec: Recording, attempt: Attempt) -> str:
    name = rec.bodies[attempt.body]
    if attempt.kind == "push":
        return f"pushed {name} (frame {attempt.frame})"
    if attempt.kind == "close":
        return (f"closed its fingers {attempt.distance * 100:.1f} cm from {name} without "
                f"grasping it (frame {attempt.frame})")
    hold = next(h for h in rec.holds(attempt.arm) if h.start == attempt.frame)
    rise = rec.rise(attempt.body, hold.start)[hold.start:hold.end]
    words = f"grasped {name} (frame {hold.start})"
    if rise.max() >= rec.profile.min_lift:
        words += f", lifted it {rise.max() * 100:.1f} cm"
        over = _carried_over(rec, attempt.body, hold.start, hold.end)
        if over:
            words += f", carried it over {', '.join(over)}"
    return words + (" and held it to the end" if hold.end is None else
                    f" and let go of it at frame {hold.end}")


def _carried_over(rec: Recording, body: int, start: int, end: int | None) -> list[str]:
    """The bodies the held body passed over while lifted, but those it was taken from and
    let go over."""
    lifted = np.zeros(len(rec.trajectory), dtype=bool)
    lifted[start:end] = rec.rise(body, start)[start:end] >= rec.profile.min_lift
    path = rec.xy[:, body]
    ends = [start, rec.last if end is None else end]
    over = [P.over_footprint(path, rec.xy[:, b], rec.half[b, :2]) for b in range(len(rec.bodies))]
    return [rec.bodies[b] for b in range(len(rec.bodies)) if b != body and
            (over[b] & lifted).any() and not over[b][ends].any()]


def _moved(rec: Recording, body: int) -> bool:
    shift = float(np.linalg.norm(rec.positions[-1, body] - rec.positions[0, body]))
    return shift >= rec.profile.push_moved or rec.tilt_deg(body) > rec.profile.topple_deg


def _ended(rec: Recording, body: int) -> str:
    name = rec.bodies[body]
    if rec.z[-1, body] < rec.scene.table_height:
        return f"{name} fell off the table"
    shift = rec.xy[-1, body] - rec.xy[0, body]
    words = (f"{name} ended {where(rec, body, rec.last)} (moved "
             f"{np.linalg.norm(shift) * 100:.1f} cm {HEADINGS[_side(shift)]})")
    if rec.tilt_deg(body) > rec.profile.topple_deg:
        words += ", knocked over"
    return words


def where(rec: Recording, body: int, frame: int) -> str:
    """Where a body is at a frame: on or in the body under it, else beside the nearest one."""
    others = np.array([b for b in range(len(rec.bodies)) if b != body])
    offsets = rec.xy[frame, body] - rec.xy[frame, others]
    nearest = int(np.argmin(np.linalg.norm(offsets, axis=1)))
    other, offset = int(others[nearest]), offsets[nearest]
    name = rec.bodies[other]
    if np.all(np.abs(offset) <= rec.half[other, :2]) and rec.z[frame, body] > rec.z[frame, other]:
        kind = rec.scene.bodies[name].kind
        return f"{'in' if kind == 'bowl' else 'on'} {name}"
    return f"{SIDES[_side(offset)]} {name}"


def _side(vector: np.ndarray) -> str:
    """The direction relation a planar vector points along most."""
    return max(DIRECTIONS, key=lambda r: float(vector @ np.array(DIRECTIONS[r])))
