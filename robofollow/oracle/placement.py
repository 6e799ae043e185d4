"""Setting down, one rule for relations, stacks, bowls and labels: where a carried object was
let go of (`deliveries`), whether it was aimed at the right place (Intent) and came to rest there
within the precision tolerances (Execution), and the exact tests of a final state (`rests_*`,
which completion reads)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from robofollow.compiler.planning.goals import GoalNode
from robofollow.compiler.scene.world import DIRECTIONS
from robofollow.oracle import predicates as P
from robofollow.oracle.instead import where
from robofollow.oracle.outcome import Outcome, cm
from robofollow.oracle.recording import Recording, arm_index
from robofollow.trajectory import yaw


@dataclass(frozen=True, slots=True)
class Delivery:
    """Where a carried object was let go of (or, still held at the end, brought lowest)."""

    frame: int
    released: bool
    height: float  # m: its bottom above the surface under it, then
    rest: int | None  # the frame it came to rest after release


def deliveries(rec: Recording, arm: int, body: int, after: int) -> tuple[Delivery, ...]:
    """Each time the arm let go of `body` after frame `after` (the lift), in order; a hold
    lasting to the end counts where the body came lowest, if within `set_down_height`. Only
    at least `carry_min` (xy) from where that hold took it: putting an object back where it
    was taken from, or never carrying it away, is not setting it down anywhere."""
    def compute() -> tuple[Delivery, ...]:
        p, found = rec.profile, []
        for hold in rec.holds(arm):
            if hold.body != body or (hold.end is not None and hold.end <= after):
                continue
            taken = rec.xy[hold.start, body]
            away = np.linalg.norm(rec.xy[:, body] - taken, axis=1) >= p.carry_min
            if hold.end is not None:
                if away[hold.end]:
                    height = rec.heights_above_surface(body, slice(hold.end, hold.end + 1))[0]
                    found.append(Delivery(hold.end, True, float(height),
                                          rec.settled(body, hold.end)))
                continue
            first = max(after, hold.start)
            heights = rec.heights_above_surface(body, slice(first, None))
            low = np.flatnonzero((heights <= p.set_down_height) & away[first:])
            if len(low):
                lowest = int(low[np.argmin(heights[low])])
                found.append(Delivery(first + lowest, False, float(heights[lowest]), None))
        return tuple(found)
    return rec.cached(("deliveries", arm, body, after), compute)


Check = Callable[[Recording, dict, int], "str | None"]  # (rec, params, frame) -> what is wrong


def _placed(rec: Recording, node: GoalNode, marks: dict, aim: Check, exact: Check,
            wanted: str) -> Outcome:
    """Intent: a delivery passes `aim` (the right side, bowl, label). Execution: such a
    delivery was a release low over the surface (not a drop), and where the object came to
    rest passes `exact` (distance, resting, orientation)."""
    intent, execution = node.intent.params, node.execution.params
    name = intent["object"]
    if "lift" not in marks:
        return Outcome(False, False, None, f"{name} was never lifted")
    found = deliveries(rec, arm_index(node.arm), rec.index(name), marks["lift"])
    if not found:
        return Outcome(False, False, None, f"{name} was never set down or let go of away "
                       "from where it was taken")
    aimed = [d for d in found if aim(rec, intent, d.frame) is None]
    if not aimed:
        first = found[0]
        placed, wrong = where(rec, rec.index(name), first.frame), aim(rec, intent, first.frame)
        return Outcome(False, False, first.frame, f"{name} was {_let_go(first)} {placed}, " + (
            f"but {wrong}" if placed == wanted else f"not {wanted} ({wrong})"))
    marks["objective"], marks["rest"] = aimed[0].frame, aimed[0].rest
    problems = []
    for delivery in aimed:
        problem = _placing_problem(rec, execution, delivery, exact)
        if problem is None:
            marks["release"], marks["rest"] = delivery.frame, delivery.rest
            return Outcome(True, True, aimed[0].frame, f"{name} released {wanted} at frame "
                           f"{delivery.frame}, at rest from frame {delivery.rest}")
        problems.append(problem)
    return Outcome(True, False, aimed[0].frame, f"{name} was brought {wanted} at frame "
                   f"{aimed[0].frame}, but {problems[0]}")


def _let_go(delivery: Delivery) -> str:
    return "released" if delivery.released else "held"


def _placing_problem(rec: Recording, params: dict, delivery: Delivery,
                     exact: Check) -> str | None:
    if not delivery.released:
        return "it was never released"
    if delivery.height > rec.profile.set_down_height:
        return (f"it was dropped from {cm(delivery.height)} above the surface (a placement "
                f"lets go within {cm(rec.profile.set_down_height)})")
    problem = exact(rec, params, delivery.rest)
    return None if problem is None else f"where it came to rest, {problem}"


def _nearest(rec: Recording, body: int, frame: int, kinds: tuple[str, ...] | None) -> int:
    """The other body (of those kinds, if given) nearest `body` in the plane at `frame`."""
    others = [b for b in range(len(rec.bodies)) if b != body and
              (kinds is None or rec.scene.bodies[rec.bodies[b]].kind in kinds)]
    gaps = np.linalg.norm(rec.xy[frame, others] - rec.xy[frame, body], axis=1)
    return others[int(np.argmin(gaps))]


def _aimed_at(kinds: tuple[str, ...] | None, key: str) -> Check:
    """Delivered nearest the asked body (of the kinds), within the aim radius."""
    def check(rec: Recording, p: dict, frame: int) -> str | None:
        source, target = rec.index(p["object"]), rec.index(p[key])
        nearest = _nearest(rec, source, frame, kinds)
        gap = float(np.linalg.norm(rec.xy[frame, source] - rec.xy[frame, target]))
        if nearest != target:
            return f"nearest {rec.bodies[nearest]}"
        if gap > p["radius"]:
            return f"{cm(gap)} from {p[key]}'s centre"
        return None
    return check


def _towards(rec: Recording, p: dict, frame: int) -> str | None:
    """Delivered on the asked side of the landmark, whatever the precision, as far as a
    relation reaches ('next to': any side); 'next to': the landmark is the nearest body."""
    source, landmark = rec.index(p["object"]), rec.index(p["landmark"])
    offset = rec.xy[frame, source] - rec.xy[frame, landmark]
    distance = float(np.linalg.norm(offset))
    if distance > p["reach"]:
        return f"{cm(distance)} from {p['landmark']}, beyond a relation's {cm(p['reach'])}"
    direction = DIRECTIONS.get(p["relation"])
    if direction is None:
        nearest = _nearest(rec, source, frame, None)
        return None if nearest == landmark else f"nearest {rec.bodies[nearest]}"
    return None if P.in_cone(offset, direction, p["cone_deg"]) else "on another side"


def rests_in_relation(rec: Recording, p: dict, frame: int) -> str | None:
    source, landmark = rec.index(p["object"]), rec.index(p["landmark"])
    offset = rec.xy[frame, source] - rec.xy[frame, landmark]
    distance = float(np.linalg.norm(offset))
    direction = DIRECTIONS.get(p["relation"])
    if direction is not None and not P.in_cone(offset, direction, p["cone_deg"]):
        return f"it is not {p['relation'].replace('_', ' ')} {p['landmark']}"
    if distance > p["range"]:
        return f"it is {cm(distance)} from {p['landmark']} (at most {cm(p['range'])})"
    height = float(rec.bottom(source)[frame] - rec.scene.table_height)
    if abs(height) > p["rest"]:
        return f"it is not on the table ({cm(height)} above it)"
    return None


def rests_on(rec: Recording, p: dict, frame: int) -> str | None:
    source, target = rec.index(p["object"]), rec.index(p["target"])
    offset = float(np.linalg.norm(rec.xy[frame, source] - rec.xy[frame, target]))
    if offset > p["xy"]:
        return f"it is {cm(offset)} off {p['target']}'s centre (at most {cm(p['xy'])})"
    gap = float(rec.bottom(source)[frame] - rec.top(target)[frame])
    if gap < -p["clearance"] or gap > p["rest"]:
        return f"it is not resting on {p['target']} ({cm(gap)} above its top)"
    return None


def rests_in(rec: Recording, p: dict, frame: int) -> str | None:
    source, bowl = rec.index(p["object"]), rec.index(p["bowl"])
    offset = float(np.linalg.norm(rec.xy[frame, source] - rec.xy[frame, bowl]))
    rise = float(rec.z[frame, source] - rec.z[frame, bowl])
    if offset > p["xy"] or rise > p["height"]:
        return f"it is not in {p['bowl']} ({cm(offset)} from its axis, {cm(rise)} above it)"
    return None


def _turned(rec: Recording, p: dict, frame: int) -> str | None:
    source = rec.index(p["object"])
    angle = float(yaw(rec.trajectory.quaternions[frame, source]))
    error = math.degrees(P.axis_error(angle, math.radians(p["yaw_deg"] or 0.0)))
    if error > p["tolerance_deg"]:
        return f"turned {error:.0f} deg off the asked yaw (at most {p['tolerance_deg']:.0f})"
    return None


def _aimed_at_label(rec: Recording, p: dict, frame: int) -> str | None:
    return _aimed_at(("label",), "target")(rec, p, frame) or _turned(rec, p, frame)


def rests_on_label(rec: Recording, p: dict, frame: int) -> str | None:
    source, label = rec.index(p["object"]), rec.index(p["target"])
    offset = np.abs(rec.xy[frame, source] - rec.xy[frame, label])
    if np.any(offset > rec.half[label, :2]):
        return f"its centre is off {p['target']}"
    gap = float(rec.bottom(source)[frame] - rec.top(label)[frame])
    if abs(gap) > p["rest"]:
        return f"it is not resting on {p['target']} ({cm(gap)} above it)"
    return _turned(rec, p, frame)


def relative_placement(rec: Recording, node: GoalNode, marks: dict) -> Outcome:
    p = node.intent.params
    wanted = f"{p['relation'].replace('_', ' ')} {p['landmark']}"
    return _placed(rec, node, marks, _towards, rests_in_relation, wanted)


def stack(rec: Recording, node: GoalNode, marks: dict) -> Outcome:
    return _placed(rec, node, marks, _aimed_at(None, "target"), rests_on,
                   f"on {node.intent.params['target']}")


def bowl(rec: Recording, node: GoalNode, marks: dict) -> Outcome:
    return _placed(rec, node, marks, _aimed_at(("bowl",), "bowl"), rests_in,
                   f"in {node.intent.params['bowl']}")


def orientation(rec: Recording, node: GoalNode, marks: dict) -> Outcome:
    return _placed(rec, node, marks, _aimed_at_label, rests_on_label,
                   f"on {node.intent.params['target']}")
