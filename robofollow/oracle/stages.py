"""Each goal-DAG stage grounded on a Recording's physical events: did the policy mean it
(Intent: the right object, side, bowl, label, waypoint), did it do it (Execution: grasped and
lifted, released low, at rest within the precision tolerances), from which frame, and why not.

A stage evaluator reads its node's predicate parameters and the frames earlier stages of the
same step left in `marks` (attempt, hold, lift, release, objective, rest) and returns an
Outcome. Gating, weights, the arm rules and completion are the scorer's business.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from robofollow.compiler.spec import TABLE_HEIGHT
from robofollow.compiler.world import DIRECTIONS
from robofollow.oracle import predicates as P
from robofollow.oracle.instead import where
from robofollow.oracle.recording import Recording, arm_index
from robofollow.trajectory import ARMS, yaw


@dataclass(frozen=True, slots=True)
class Outcome:
    intent: bool
    execution: bool
    frame: int | None  # where the stage's intent was first met (or the deciding frame)
    reason: str


# what counts as going for a step's object: a grasp or a close (for a push: a grasp or a
# push); brushing an object on the way is judged by its effect, in the finish
GRASPING = ("grasp", "close")
GOING_FOR = {"pick": GRASPING, "place": GRASPING, "push": ("grasp", "push")}


def cm(metres: float) -> str:
    return f"{metres * 100:.1f} cm"


# -- source grounding -------------------------------------------------------------------------

def went_for(rec: Recording, node: dict, marks: dict) -> Outcome:
    """Intent: the first body the arm grasps or closes its fingers at (from `marks['start']`)
    is the source. Execution: the arm then holds the source and lifts it (and not the body
    it stood on with it)."""
    params, lift = node["intent"]["params"], node["execution"]["params"]["min_lift"]
    arm, source, name = arm_index(params["arm"]), rec.index(params["object"]), params["object"]
    attempt = rec.first_attempt(arm, marks.get("start", 0), GOING_FOR["pick"])
    if attempt is None:
        return Outcome(False, False, None, f"the {params['arm']} arm never went for an object")
    t = marks["attempt"] = attempt.frame
    if attempt.body != source:
        return Outcome(False, False, t, f"the {params['arm']} arm first "
                       f"{attempt.words(rec.bodies)}, not {name}")
    found = attempt.words(rec.bodies)
    holds = [h for h in rec.holds(arm) if h.body == source and h.start >= t]
    if not holds:
        return Outcome(True, False, t, f"{found}, but never grasped it")
    best = 0.0
    for hold in holds:
        rise = rec.rise(source, hold.start)[hold.start:hold.end]
        lifted = P.first_true(rise >= rec.profile.min_lift)
        if lifted is not None and "lift" not in marks:
            marks["hold"], marks["lift"] = hold.start, hold.start + lifted
        best = max(best, float(rise.max()))
        if rise.max() >= lift:
            support = rec.support_of(source, hold.start)
            if support is not None and \
                    rec.rise(support, hold.start)[hold.start:hold.end].max() >= rec.profile.min_lift:
                return Outcome(True, False, t, f"{found}, but lifted {rec.bodies[support]} "
                               "with it")
            return Outcome(True, True, t, f"{found} and lifted it {cm(best)}")
    return Outcome(True, False, t, f"{found}, but lifted it {cm(best)} (needs {cm(lift)})")


def push_contact(rec: Recording, node: dict, marks: dict) -> Outcome:
    """Intent: the first body the arm grasps or pushes is the source, pushed. Execution: the
    gripper was closed and low when the source started to move."""
    intent, execution = node["intent"]["params"], node["execution"]["params"]
    arm, source, name = arm_index(intent["arm"]), rec.index(intent["object"]), intent["object"]
    attempt = rec.first_attempt(arm, marks.get("start", 0), GOING_FOR["push"])
    if attempt is None:
        return Outcome(False, False, None, f"the {intent['arm']} arm never pushed an object")
    t = marks["attempt"] = attempt.frame
    if attempt.body != source or attempt.kind != "push":
        return Outcome(False, False, t, f"the {intent['arm']} arm first "
                       f"{attempt.words(rec.bodies)}, not pushed {name}")
    opening = float(rec.opening[t, arm])
    if opening > execution["close"]:
        return Outcome(True, False, t, f"pushed {name} at frame {t} with the gripper open "
                       f"({opening:.2f}; closed is {execution['close']:.2f} or less)")
    height = abs(float(rec.ee[t, arm, 2] - rec.z[0, source]))
    if height > execution["height"]:
        return Outcome(True, False, t, f"pushed {name} from {cm(height)} above it (limit "
                       f"{cm(execution['height'])})")
    return Outcome(True, True, t, f"pushed {name} from frame {t}, the gripper closed")


def pushed_towards(rec: Recording, node: dict, marks: dict) -> Outcome:
    """Intent: pushed from behind, the source moves towards the target's start. Execution:
    where it comes to rest, it has moved far enough that way."""
    intent, execution = node["intent"]["params"], node["execution"]["params"]
    source, arm, t = rec.index(intent["object"]), arm_index(node["arm"]), marks["attempt"]
    direction = _direction(rec, intent)
    moved = P.progress(rec.xy[:, source] - rec.xy[0, source], direction, intent["cone_deg"])
    behind = (rec.ee[:, arm, :2] - rec.xy[:, source]) @ direction <= 0
    moved = np.where(behind, moved, 0.0)
    moved[:t] = 0.0
    best = float(moved.max())
    frame = P.first_true(moved >= intent["min_displacement"])
    what = f"{intent['object']} towards {intent['target']}"
    if frame is None:
        return Outcome(False, False, None, f"pushed {what} {cm(best)} (needs "
                       f"{cm(intent['min_displacement'])})")
    marks["objective"] = frame
    rest = marks["rest"] = rec.settled(source, int(np.argmax(moved)))
    problem = _pushed_far(rec, execution, rest)
    if problem is not None:
        return Outcome(True, False, frame, f"pushed {what}, but where it came to rest "
                       f"{problem}")
    return Outcome(True, True, frame, f"pushed {what}, at rest from frame {rest}")


def _direction(rec: Recording, p: dict) -> np.ndarray:
    """The unit direction from the source's start to the target's."""
    vector = rec.xy[0, rec.index(p["target"])] - rec.xy[0, rec.index(p["object"])]
    return vector / max(float(np.linalg.norm(vector)), 1e-9)


def _pushed_far(rec: Recording, p: dict, frame: int) -> str | None:
    """Moved far enough towards the target's start (within the cone) by `frame`."""
    source = rec.index(p["object"])
    shift = rec.xy[frame:frame + 1, source] - rec.xy[0, source]
    moved = float(P.progress(shift, _direction(rec, p), p["cone_deg"])[0])
    if moved < p["min_displacement"]:
        return (f"it had moved {cm(moved)} towards {p['target']} (needs "
                f"{cm(p['min_displacement'])})")
    return None


# -- setting down: one rule for relations, stacks, bowls and labels --------------------------

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


def _placed(rec: Recording, node: dict, marks: dict, aim: Check, exact: Check,
            wanted: str) -> Outcome:
    """Intent: a delivery passes `aim` (the right side, bowl, label). Execution: such a
    delivery was a release low over the surface (not a drop), and where the object came to
    rest passes `exact` (distance, resting, orientation)."""
    intent, execution = node["intent"]["params"], node["execution"]["params"]
    name = intent["object"]
    if "lift" not in marks:
        return Outcome(False, False, None, f"{name} was never lifted")
    found = deliveries(rec, arm_index(node["arm"]), rec.index(name), marks["lift"])
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


def _in_relation(rec: Recording, p: dict, frame: int) -> str | None:
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


def _on(rec: Recording, p: dict, frame: int) -> str | None:
    source, target = rec.index(p["object"]), rec.index(p["target"])
    offset = float(np.linalg.norm(rec.xy[frame, source] - rec.xy[frame, target]))
    if offset > p["xy"]:
        return f"it is {cm(offset)} off {p['target']}'s centre (at most {cm(p['xy'])})"
    gap = float(rec.bottom(source)[frame] - rec.top(target)[frame])
    if gap < -p["clearance"] or gap > p["rest"]:
        return f"it is not resting on {p['target']} ({cm(gap)} above its top)"
    return None


def _in_bowl(rec: Recording, p: dict, frame: int) -> str | None:
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


def _on_label(rec: Recording, p: dict, frame: int) -> str | None:
    source, label = rec.index(p["object"]), rec.index(p["target"])
    offset = np.abs(rec.xy[frame, source] - rec.xy[frame, label])
    if np.any(offset > rec.half[label, :2]):
        return f"its centre is off {p['target']}"
    gap = float(rec.bottom(source)[frame] - rec.top(label)[frame])
    if abs(gap) > p["rest"]:
        return f"it is not resting on {p['target']} ({cm(gap)} above it)"
    return _turned(rec, p, frame)


def relative_placement(rec: Recording, node: dict, marks: dict) -> Outcome:
    p = node["intent"]["params"]
    wanted = f"{p['relation'].replace('_', ' ')} {p['landmark']}"
    return _placed(rec, node, marks, _towards, _in_relation, wanted)


def stack(rec: Recording, node: dict, marks: dict) -> Outcome:
    return _placed(rec, node, marks, _aimed_at(None, "target"), _on,
                   f"on {node['intent']['params']['target']}")


def bowl(rec: Recording, node: dict, marks: dict) -> Outcome:
    return _placed(rec, node, marks, _aimed_at(("bowl",), "bowl"), _in_bowl,
                   f"in {node['intent']['params']['bowl']}")


def orientation(rec: Recording, node: dict, marks: dict) -> Outcome:
    return _placed(rec, node, marks, _aimed_at_label, _on_label,
                   f"on {node['intent']['params']['target']}")


# exact tests by execution predicate: what a final state must satisfy (completion reads them)
AT_REST = {"rests_in_relation": _in_relation, "rests_on": _on, "rests_in": _in_bowl,
           "rests_on_label": _on_label, "pushed_towards_at_rest": _pushed_far}


# -- routes -----------------------------------------------------------------------------------

def route(rec: Recording, node: dict, marks: dict) -> Outcome:
    """While carried, the object is over a body when its centre is over that body's
    footprint (at any altitude). 'Pass over W': Intent when it crosses W's column on W's side
    (nearer W than the column's other bodies, within `y` of it), Execution when it is over W.
    'Avoid X': Intent when it crosses X's column beside X (not over it there), Execution when
    it is never over X."""
    p = node["intent"]["params"]
    source, arm = rec.index(p["object"]), arm_index(node["arm"])
    since = marks.get("hold", marks["attempt"])
    carried = (rec.holding(arm) == source) & (rec.rise(source, since) >= rec.profile.min_lift)
    if not carried.any():
        return Outcome(False, False, None, f"{p['object']} was never carried")
    path, start = rec.xy[:, source], rec.world(0)
    met, said, missed = marks["attempt"], [], []
    for mode, body in p["waypoints"]:
        b = rec.index(body)
        frames, ys = P.crossings(path, float(rec.xy[0, b, 0]), p["x"])
        keep = carried[frames]
        frames, ys = frames[keep], ys[keep]
        over = P.over_footprint(path, rec.xy[:, b], rec.half[b, :2]) & carried
        if not len(frames):
            return Outcome(False, False, None, f"{p['object']} was never carried across "
                           f"{body}'s column")
        gap = np.abs(ys - rec.xy[0, b, 1])
        if mode == "via":
            side = gap <= p["y"]
            for mate in start.column_mates(body, (p["object"],)):
                side &= gap < np.abs(ys - rec.xy[0, rec.index(mate), 1])
            if not side.any():
                return Outcome(False, False, None, f"{p['object']} did not cross {body}'s "
                               f"column on its side")
            met = max(met, int(frames[side][0]))
            said.append(f"crossed {body}'s column at frame {int(frames[side][0])}")
            if not over.any():
                missed.append(f"it never passed over {body}")
            continue
        across = over[frames]
        if across.any():
            frame = int(frames[across][0])
            return Outcome(False, False, frame, f"{p['object']} crossed {body}'s column over "
                           f"it at frame {frame}")
        met = max(met, int(frames[0]))
        said.append(f"went round {body}")
        if over.any():
            missed.append(f"it passed over {body} at frame {int(np.flatnonzero(over)[0])}")
    marks["objective"] = met
    words = f"{p['object']} {' and '.join(said)}"
    if missed:
        return Outcome(True, False, met, f"{words}, but {'; '.join(missed)}")
    return Outcome(True, True, met, words)


# -- finishing --------------------------------------------------------------------------------

def finish(rec: Recording, node: dict, marks: dict) -> Outcome:
    """After the action: each working arm back home and still within the deadline, staying
    (never leaving, moving, grasping or closing at an object again); each handled object
    still held (pickups) or where it came to rest; no other object moved, knocked over or
    off the table (what pushes did is judged here, by its effect; a push's target may be
    struck, within `struck_tolerance`); the idle arm never
    grasping or closing at an object, never in the work area. Every violation is named."""
    p = node["intent"]["params"]
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


EVALUATORS = {"went_for": went_for, "first_pushed": push_contact,
              "pushed_towards": pushed_towards, "delivered_towards": relative_placement,
              "delivered_onto": stack, "delivered_into": bowl, "route_sides": route,
              "delivered_to_label": orientation, "finished": finish}
