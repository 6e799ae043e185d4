"""What the arms actually did, in words: objects grasped, lifted, carried over, set down or
pushed, read from the trajectory alone (the scorer matches it to known behaviours)."""

from __future__ import annotations

import numpy as np

from robofollow.compiler.world import DIRECTIONS
from robofollow.oracle import predicates as P
from robofollow.oracle.recording import Recording
from robofollow.trajectory import ARMS

SIDES = {"left_of": "left of", "right_of": "right of", "behind": "behind",
         "in_front_of": "in front of"}
HEADINGS = {"left_of": "to the left", "right_of": "to the right", "behind": "away",
            "in_front_of": "towards the robot"}


def describe_actions(rec: Recording) -> str:
    """One clause per grasped object and per pushed object, or 'nothing moved'."""
    clauses, handled = [], set()
    for arm, name in enumerate(ARMS):
        firsts = {}
        for grasp in rec.grasps(arm):
            firsts.setdefault(grasp.body, grasp.frame)
        for body, frame in firsts.items():
            handled.add(body)
            clauses.append(f"the {name} arm {_handled(rec, body, frame)}")
    p = rec.profile
    for body in rec.graspable:
        if body in handled:
            continue
        shift = rec.xy[-1, body] - rec.xy[0, body]
        if np.linalg.norm(shift) >= p.push_min_execution and \
                np.abs(rec.rise(body, 0)).max() <= p.on_table_tolerance:
            clauses.append(f"{rec.bodies[body]} was pushed {np.linalg.norm(shift) * 100:.1f} cm "
                           f"{HEADINGS[_side(shift)]}")
    return "; ".join(clauses) or "nothing moved"


def _handled(rec: Recording, body: int, grasp: int) -> str:
    name, p = rec.bodies[body], rec.profile
    rise = rec.rise(body, grasp)
    if rise.max() < p.min_lift:
        return f"closed on {name} without lifting it"
    lifted = rise >= p.min_lift
    ends = {body, rec.support_of(body, grasp), rec.support_of(body, rec.last)}
    over = [rec.bodies[b] for b in rec.graspable if b not in ends and
            (P.over_footprint(rec.xy[:, body], rec.xy[:, b], rec.half[b, :2]) & lifted).any()]
    words = f"picked {name}" + (f", carried it over {', '.join(over)}" if over else "")
    if lifted[-1]:
        return words + " and held it up"
    return words + f" and set it down {_where(rec, body)}"


def _where(rec: Recording, body: int) -> str:
    """Where a body rests at the end: on or in another body, else beside the nearest one."""
    end = rec.last
    others = np.array([b for b in range(len(rec.bodies)) if b != body])
    offsets = rec.xy[end, body] - rec.xy[end, others]
    nearest = int(np.argmin(np.linalg.norm(offsets, axis=1)))
    other, offset = int(others[nearest]), offsets[nearest]
    name = rec.bodies[other]
    if np.linalg.norm(offset) <= rec.half[other, :2].min() and rec.z[end, body] > rec.z[end, other]:
        kind = rec.scene.bodies[name].kind
        return f"{'in' if kind == 'bowl' else 'on'} {name}"
    return f"{SIDES[_side(offset)]} {name}"


def _side(vector: np.ndarray) -> str:
    """The direction relation a planar vector points along most."""
    return max(DIRECTIONS, key=lambda r: float(vector @ np.array(DIRECTIONS[r])))
