"""Each goal-DAG stage grounded on a Recording's physical events: did the policy mean it
(Intent: the right object, side, bowl, label, waypoint), did it do it (Execution: grasped and
lifted, released low, at rest within the precision tolerances), from which frame, and why not.

A stage evaluator reads its node's predicate parameters and the frames earlier stages of the
same step left in `marks` (attempt, hold, lift, release, objective, rest) and returns an
Outcome (outcome.py). Source grounding, pushes and routes are evaluated here, setting down in
placement.py and the finishing stage in finish.py; EVALUATORS names each predicate's evaluator.
Gating, weights, the arm rules and completion are the scorer's business.
"""

from __future__ import annotations

import numpy as np

from robofollow.compiler.planning.goals import GoalNode
from robofollow.oracle import predicates as P
from robofollow.oracle.finish import finish
from robofollow.oracle.outcome import GOING_FOR, Outcome, cm
from robofollow.oracle.placement import (
    bowl,
    orientation,
    relative_placement,
    rests_in,
    rests_in_relation,
    rests_on,
    rests_on_label,
    stack,
)
from robofollow.oracle.recording import Recording, arm_index

# -- source grounding -------------------------------------------------------------------------

def went_for(rec: Recording, node: GoalNode, marks: dict) -> Outcome:
    """Intent: the first body the arm grasps or closes its fingers at (from `marks['start']`)
    is the source. Execution: the arm then holds the source and lifts it (and not the body
    it stood on with it)."""
    params, lift = node.intent.params, node.execution.params["min_lift"]
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


def push_contact(rec: Recording, node: GoalNode, marks: dict) -> Outcome:
    """Intent: the first body the arm grasps or pushes is the source, pushed. Execution: the
    gripper was closed and low when the source started to move."""
    intent, execution = node.intent.params, node.execution.params
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


def pushed_towards(rec: Recording, node: GoalNode, marks: dict) -> Outcome:
    """Intent: pushed from behind, the source moves towards the target's start. Execution:
    where it comes to rest, it has moved far enough that way."""
    intent, execution = node.intent.params, node.execution.params
    source, arm, t = rec.index(intent["object"]), arm_index(node.arm), marks["attempt"]
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


# exact tests by execution predicate: what a final state must satisfy (completion reads them)
AT_REST = {"rests_in_relation": rests_in_relation, "rests_on": rests_on, "rests_in": rests_in,
           "rests_on_label": rests_on_label, "pushed_towards_at_rest": _pushed_far}


# -- routes -----------------------------------------------------------------------------------

def route(rec: Recording, node: GoalNode, marks: dict) -> Outcome:
    """While carried, the object is over a body when its centre is over that body's
    footprint (at any altitude). 'Pass over W': Intent when it crosses W's column on W's side
    (nearer W than the column's other bodies, within `y` of it), Execution when it is over W.
    'Avoid X': Intent when it crosses X's column beside X (not over it there), Execution when
    it is never over X."""
    p = node.intent.params
    source, arm = rec.index(p["object"]), arm_index(node.arm)
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


# each predicate's evaluator: source grounding, pushes and routes here, setting down in
# placement.py, the finish in finish.py
EVALUATORS = {"went_for": went_for, "first_pushed": push_contact,
              "pushed_towards": pushed_towards, "delivered_towards": relative_placement,
              "delivered_onto": stack, "delivered_into": bowl, "route_sides": route,
              "delivered_to_label": orientation, "finished": finish}
