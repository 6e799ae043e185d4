"""The finishing stage of every task: the arms back home and still, the handled objects left as
put, nothing else disturbed, and the other arm out of the work area."""

from __future__ import annotations

import numpy as np

from robofollow.compiler.planning.goals import GoalNode
from robofollow.compiler.scene.spec import TABLE_HEIGHT
from robofollow.oracle import predicates as P
from robofollow.oracle.outcome import GRASPING, Outcome, cm
from robofollow.oracle.recording import Recording, arm_index
from robofollow.trajectory import ARMS


def finish(rec: Recording, node: GoalNode, marks: dict) -> Outcome:
    """After the action: each working arm back home and still within the deadline, staying
    (never leaving, moving, grasping or closing at an object again); each handled object
    still held (pickups) or where it came to rest; no other object moved, knocked over or
    off the table (what pushes did is judged here, by its effect; a push's target may be
    struck, within `struck_tolerance`); the idle arm never
    grasping or closing at an object, never in the work area. Every violation is named."""
    p = node.intent.params
    done, rests = marks.get("completion", 0), dict(marks.get("rests", ()))
    problems = []
    for name in dict.fromkeys(p["arms"]):
        problems += rec.cached(("home", name, done, p["home_radius"], p["frames"],
                                p["still_radius"], p["deadline_frames"], p["leave_radius"]),
                               lambda name=name: _home_and_still(rec, arm_index(name), name,
                                                                 done, p))
    for body_name, keep, arm_name in p["keep"]:
        problems += _kept(rec, rec.index(body_name), keep, arm_index(arm_name),
                          rests.get(body_name), p)
    handled = frozenset(rec.index(b) for b, _, _ in p["keep"])
    struck = frozenset(rec.index(b) for b in p["struck"])
    problems += rec.cached(("disturbed", handled, struck, p["disturb"], p["struck_tolerance"],
                            p["topple_deg"]), lambda: _disturbed(rec, handled, struck, p))
    for name in (a for a in ARMS if a not in p["arms"]):
        problems += rec.cached(("idle", name, tuple(map(tuple, p["operation_area"]))),
                               lambda name=name: _idle(rec, arm_index(name), name, p))
    if problems:
        return Outcome(False, False, done, "; ".join(problems))
    return Outcome(True, True, done, "back home and still, nothing else disturbed"
                   if p["arms"] else "stayed still, nothing disturbed")


def _home_and_still(rec: Recording, arm: int, name: str, done: int, p: dict) -> list[str]:
    ee, home = rec.ee[:, arm], rec.ee[0, arm]
    away = np.linalg.norm(ee - home, axis=1)
    still = rec.still(arm, p["frames"], p["still_radius"])
    settled = P.holds_for(away <= p["home_radius"], p["frames"]) & still
    arrived = P.first_true(settled, done)
    if arrived is None:
        return [(f"the {name} arm did not come home and keep still (within "
                 f"{cm(p['home_radius'])} of home, moving less than {cm(p['still_radius'])} "
                 f"over {p['frames']} frames)")]
    problems = []
    if arrived - done > p["deadline_frames"]:
        problems.append(f"the {name} arm came home {arrived - done} frames after finishing "
                        f"(limit {p['deadline_frames']})")
    left = P.first_true(away > p["leave_radius"], arrived)
    moved = P.first_true(~still, arrived)
    if left is not None:
        problems.append(f"the {name} arm left home again at frame {left} "
                        f"({cm(float(away[arrived:].max()))} away)")
    elif moved is not None:
        problems.append(f"the {name} arm moved again at home from frame {moved}")
    again = rec.first_attempt(arm, done + 1, GRASPING)
    closes = rec.closes(arm)
    shut = closes[closes > done]
    if again is not None:
        problems.append(f"the {name} arm {again.words(rec.bodies)} after finishing")
    elif len(shut):
        problems.append(f"the {name} arm closed its gripper again at frame {int(shut[0])}")
    return problems


def _kept(rec: Recording, body: int, keep: str, arm: int, rest: int | None,
          p: dict) -> list[str]:
    name = rec.bodies[body]
    if keep == "held":
        held = rec.holding(arm) == body
        if held[-1]:
            return []
        taken = P.first_true(held)
        if taken is None:
            return [f"{name} was never held by the {ARMS[arm]} arm"]
        return [f"{name} was let go of at frame {P.first_true(~held, taken)}"]
    if rest is None:
        return [f"{name} was never let go of"]
    moved = np.linalg.norm(rec.positions[rest:, body] - rec.positions[rest, body], axis=1)
    if moved.max() > p["stay"]:
        frame = rest + int(np.argmax(moved > p["stay"]))
        return [(f"{name} moved {cm(float(moved.max()))} from where it came to rest (from "
                 f"frame {frame})")]
    return []


def _disturbed(rec: Recording, handled: frozenset[int], struck: frozenset[int],
               p: dict) -> list[str]:
    problems = []
    table = rec.scene.table_height
    for body in rec.movable:
        if body in handled:
            continue
        tolerance = p["struck_tolerance"] if body in struck else p["disturb"]
        name = rec.bodies[body]
        holder = next((ARMS[a] for a in range(2) if rec.holding(a)[-1] == body), None)
        moved = float(np.linalg.norm(rec.positions[-1, body] - rec.positions[0, body]))
        if holder is not None:
            problems.append(f"{name} is held by the {holder} arm")
        elif rec.z[-1, body] < table:
            problems.append(f"{name} fell off the table")
        elif rec.tilt_deg(body) > p["topple_deg"]:
            problems.append(f"{name} was knocked over")
        elif moved > tolerance:
            problems.append(f"{name} was moved {cm(moved)} (at most {cm(tolerance)})")
    return problems


def _idle(rec: Recording, arm: int, name: str, p: dict) -> list[str]:
    problems = []
    attempt = rec.first_attempt(arm, kinds=GRASPING)
    if attempt is not None:
        problems.append(f"the idle {name} arm {attempt.words(rec.bodies)}")
    area = np.array(p["operation_area"], dtype=float)
    area[2] += rec.scene.table_height - TABLE_HEIGHT  # (the z band moves with the table)
    entered = P.first_true(P.inside_box(rec.ee[:, arm], area))
    if entered is not None:
        problems.append(f"the idle {name} arm entered the work area at frame {entered}")
    return problems
