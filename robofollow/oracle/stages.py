"""Each goal-DAG stage grounded on a Recording: did the policy mean it (Intent), did it do it
(Execution), from which frame, and why not.

A stage evaluator reads its node's predicate parameters and the frames earlier stages of the
same step left in `marks` (grasp, lift, release, objective) and returns an Outcome. Gating and
weights are the scorer's business, not the evaluators'.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from robofollow.compiler.behaviour import Step
from robofollow.compiler.splits import passes_over
from robofollow.compiler.world import DIRECTIONS
from robofollow.oracle import predicates as P
from robofollow.oracle.recording import Recording, arm_index
from robofollow.trajectory import ARMS, yaw


@dataclass(frozen=True, slots=True)
class Outcome:
    intent: bool
    execution: bool
    frame: int | None  # where the stage's intent was first met (or the deciding frame)
    reason: str


def _cm(metres: float) -> str:
    return f"{metres * 100:.1f} cm"


def grasp(rec: Recording, node: dict, marks: dict) -> Outcome:
    """Source grounding: the arm's first grasp attempt (from `marks['start']`) is on the
    source; Execution: the source then rises by the stage's lift (and its support does not)."""
    params, lift = node["intent"]["params"], node["execution"]["params"]["min_lift"]
    arm, source = arm_index(params["arm"]), rec.index(params["object"])
    attempt = rec.first_grasp(arm, marks.get("start", 0))
    if attempt is None:
        return Outcome(False, False, None, f"the {params['arm']} arm never closed on an object")
    t = attempt.frame
    marks["grasp"] = t
    if attempt.body != source:
        return Outcome(False, False, t, f"the {params['arm']} arm first closed on "
                       f"{rec.bodies[attempt.body]} (frame {t}), not {params['object']}")
    rise = rec.rise(source, t)
    lifted = P.first_true(rise >= rec.profile.min_lift, t)
    if lifted is not None:
        marks["lift"] = lifted
    found = f"closed on {params['object']} at frame {t} ({_cm(attempt.distance)} off)"
    best = float(rise[t:].max())
    if best < lift:
        return Outcome(True, False, t, f"{found}, but lifted it {_cm(best)} (needs {_cm(lift)})")
    support = rec.support_of(source, t)
    if support is not None and rec.rise(support, t)[t:].max() >= rec.profile.min_lift:
        return Outcome(True, False, t, f"{found}, but lifted {rec.bodies[support]} with it")
    return Outcome(True, True, t, f"{found} and lifted it {_cm(best)}")


def push_contact(rec: Recording, node: dict, marks: dict) -> Outcome:
    """Push contact: with the gripper closed, the arm is at the source (nearest, within the
    radius) while the source slides on the table; Execution: low enough at first contact."""
    p, intent, execution = rec.profile, node["intent"]["params"], node["execution"]["params"]
    arm, source = arm_index(intent["arm"]), rec.index(intent["object"])
    t = P.first(rec.closes(arm, intent["close"]))
    if t is None:
        return Outcome(False, False, None, f"the {intent['arm']} arm never closed its gripper "
                       "to push")
    marks["grasp"] = t
    shift = np.linalg.norm(rec.xy[:, source] - rec.xy[t, source], axis=1)
    sliding = (shift >= p.push_moved) & (np.abs(rec.rise(source, 0)) <= p.on_table_tolerance)
    sliding[:t + 1] = False
    frames = np.flatnonzero(sliding)
    if not len(frames):
        return Outcome(False, False, None, f"{intent['object']} never slid on the table")
    ee = rec.ee[frames, arm, :2]
    distances = np.linalg.norm(rec.xy[frames][:, rec.graspable] - ee[:, None], axis=2)
    nearest = rec.graspable[np.argmin(distances, axis=1)]
    gap = np.linalg.norm(rec.xy[frames, source] - ee, axis=1)
    at_source = nearest == source
    touching = np.flatnonzero(at_source & (gap < intent["radius"]))
    if not len(touching):
        return Outcome(False, False, int(frames[0]), f"{intent['object']} slid, but the "
                       f"{intent['arm']} gripper was not at it")
    contact = int(frames[touching[0]])
    height = abs(rec.ee[frames[0], arm, 2] - rec.z[0, source])
    if height > execution["height"]:
        return Outcome(True, False, contact, f"pushed {intent['object']} from {_cm(height)} "
                       f"above it (limit {_cm(execution['height'])})")
    if not np.any(at_source & (gap < execution["radius"])):
        return Outcome(True, False, contact, f"lost contact with {intent['object']}")
    return Outcome(True, True, contact, f"pushed {intent['object']} from frame {contact}")


def pushed_towards(rec: Recording, node: dict, marks: dict) -> Outcome:
    """The source moves towards the target's start, pushed from behind (Intent and Execution
    differ in the displacement they need)."""
    intent, execution = node["intent"]["params"], node["execution"]["params"]
    source, target = rec.index(intent["object"]), rec.index(intent["target"])
    arm, t = arm_index(node["arm"]), marks["grasp"]
    direction = rec.xy[0, target] - rec.xy[0, source]
    direction = direction / max(np.linalg.norm(direction), 1e-9)
    moved = P.progress(rec.xy[:, source] - rec.xy[t, source], direction, intent["cone_deg"])
    behind = (rec.ee[:, arm, :2] - rec.xy[:, source]) @ direction <= 0
    moved = np.where(behind, moved, 0.0)
    moved[:t + 1] = 0.0
    best = float(moved.max())
    frame = P.first_true(moved >= intent["min_displacement"])
    if frame is None:
        return Outcome(False, False, None, f"{intent['object']} moved {_cm(best)} towards "
                       f"{intent['target']} (needs {_cm(intent['min_displacement'])})")
    marks["objective"] = frame
    done = best >= execution["min_displacement"]
    return Outcome(True, done, frame, f"pushed {intent['object']} {_cm(best)} towards "
                   f"{intent['target']}" + ("" if done else
                                            f" (needs {_cm(execution['min_displacement'])})"))


def _release(rec: Recording, arm: int, marks: dict) -> int | None:
    release = P.first(rec.opens(arm), marks.get("lift", marks["grasp"]) + 1)
    if release is not None:
        marks["release"] = release
    return release


def _placed(rec: Recording, node: dict, marks: dict, holds: tuple[np.ndarray, np.ndarray],
            where: str, steady: np.ndarray | None = None) -> Outcome:
    """Shared shape of the placing stages: Intent when `holds` first after the lift with the
    intent thresholds; Execution when the final thresholds hold at release and at the end
    (and `steady` from release on)."""
    intent_holds, final_holds = holds
    source = node["intent"]["params"]["object"]
    start = marks.get("lift")
    if start is None:
        return Outcome(False, False, None, f"{source} was never lifted")
    frame = P.first_true(intent_holds, start)
    if frame is None:
        return Outcome(False, False, None, f"{source} never got {where}")
    marks["objective"] = frame
    release = _release(rec, arm_index(node["arm"]), marks)
    if release is None:
        return Outcome(True, False, frame, f"{source} got {where} at frame {frame} but was "
                       "never released")
    if not final_holds[release]:
        return Outcome(True, False, frame, f"{source} was released at frame {release}, not "
                       f"{where}")
    if not final_holds[-1] or (steady is not None and not steady[release:].all()):
        return Outcome(True, False, frame, f"{source} was released {where} but did not stay")
    return Outcome(True, True, frame, f"{source} released {where} at frame {release}")


def relative_placement(rec: Recording, node: dict, marks: dict) -> Outcome:
    """Set down on the table in the asked relation to a landmark (cone and distance)."""
    p = node["intent"]["params"]
    source, landmark = rec.index(p["object"]), rec.index(p["landmark"])
    offset = rec.xy[:, source] - rec.xy[:, landmark]
    related = P.in_cone(offset, DIRECTIONS.get(p["relation"]), p["range"], p["cone_deg"])
    down = P.resting_on(rec.bottom(source), rec.scene.table_height, p["on_table"])
    holds = related & down
    where = f"{p['relation'].replace('_', ' ')} {p['landmark']} on the table"
    return _placed(rec, node, marks, (holds, holds), where)


def stack(rec: Recording, node: dict, marks: dict) -> Outcome:
    """Brought over the target (Intent), released resting on it (Execution)."""
    intent, execution = node["intent"]["params"], node["execution"]["params"]
    source, target = rec.index(intent["object"]), rec.index(intent["target"])
    heights = rec.half[source, 2] + rec.half[target, 2]
    a, b = rec.positions[:, source], rec.positions[:, target]
    over = P.stacked(a, b, heights, intent["radius"], intent["clearance"])
    on = P.stacked(a, b, heights, execution["xy"], execution["clearance"])
    steady = a[:, 2] - b[:, 2] >= heights - execution["clearance"]
    return _placed(rec, node, marks, (over, on), f"on {intent['target']}", steady)


def bowl(rec: Recording, node: dict, marks: dict) -> Outcome:
    """Lowered into the bowl (Intent), released there and left in it (Execution)."""
    p = node["intent"]["params"]
    source, target = rec.index(p["object"]), rec.index(p["bowl"])
    inside = P.in_bowl(rec.positions[:, source], rec.positions[:, target], p["xy"], p["height"])
    return _placed(rec, node, marks, (inside, inside), f"in {p['bowl']}")


def route(rec: Recording, node: dict, marks: dict) -> Outcome:
    """While carried, the source crosses each waypoint's column over the right body: closer
    to it than to the column's other bodies, and (for 'avoid X') never over X itself."""
    p = node["intent"]["params"]
    source = rec.index(p["object"])
    lifted = rec.rise(source, marks["grasp"]) >= rec.profile.min_lift
    lifted[:marks["grasp"]] = False
    path = rec.xy[:, source]
    start, crossed, met = rec.world(0), [], marks["grasp"]
    for mode, body in p["waypoints"]:
        step = Step(action="place", arm=None, source=p["object"], waypoints=((mode, body),))
        rights = passes_over(step, start)
        wrongs = [body] if mode == "avoid" else start.column_mates(body, (p["object"],))
        for right in rights:
            frame = _crossed(rec, path, lifted, right, wrongs, p)
            if frame is None:
                return Outcome(False, False, None, f"{p['object']} was not carried over {right}")
            crossed.append(f"{right} at frame {frame}")
            met = max(met, frame)
        if mode == "avoid":
            avoided = rec.index(body)
            over = P.over_footprint(path, rec.xy[:, avoided], rec.half[avoided, :2]) & lifted
            if over.any():
                frame = int(np.flatnonzero(over)[0])
                return Outcome(False, False, frame, f"{p['object']} passed over {body} at "
                               f"frame {frame}")
    marks["objective"] = met
    avoided = [body for mode, body in p["waypoints"] if mode == "avoid"]
    words = ([f"was carried over {', '.join(crossed)}"] if crossed else []) + \
        ([f"never over {', '.join(avoided)}"] if avoided else [])
    return Outcome(True, True, met, f"{p['object']} {' and '.join(words)}")


def _crossed(rec: Recording, path: np.ndarray, lifted: np.ndarray, right: str,
             wrongs: list[str], p: dict) -> int | None:
    """The first frame the carried path crosses `right`'s column over it, not the others."""
    c = rec.xy[0, rec.index(right)]
    frames, ys = P.crossings(path, float(c[0]), p["x"])
    keep = lifted[frames]
    frames, ys = frames[keep], ys[keep]
    gap = np.abs(ys - c[1])
    ok = gap < p["y"]
    for wrong in wrongs:
        other = np.abs(ys - rec.xy[0, rec.index(wrong), 1])
        ok &= (other > p["clear_y"]) & (gap < other)
    return int(frames[ok][0]) if ok.any() else None


def orientation(rec: Recording, node: dict, marks: dict) -> Outcome:
    """At the final frame the source rests on the target label, its centre within the label
    edge, turned as asked (modulo 180 degrees; Intent and Execution differ in tolerance)."""
    intent, execution = node["intent"]["params"], node["execution"]["params"]
    source, target = rec.index(intent["object"]), rec.index(intent["target"])
    end = rec.last
    offset = float(np.linalg.norm(rec.xy[end, source] - rec.xy[end, target]))
    down = abs(rec.bottom(source)[end] - rec.top(target)[end]) <= rec.profile.on_table_tolerance
    if offset >= intent["edge"] or not down:
        where = "not resting" if not down else f"{_cm(offset)} from its centre"
        return Outcome(False, False, end, f"{intent['object']} ends {where} on {intent['target']}")
    angle = float(yaw(rec.trajectory.quaternions[end, source]))
    error = math.degrees(P.axis_error(angle, math.radians(intent["yaw_deg"] or 0.0)))
    turned = f"{intent['object']} ends on {intent['target']}, {error:.0f} deg off the asked yaw"
    return Outcome(error <= intent["tolerance_deg"], error <= execution["tolerance_deg"], end,
                   turned)


def finish(rec: Recording, node: dict, marks: dict) -> Outcome:
    """After the action: each working arm comes home within the deadline and stays (never
    leaving again, never re-closing); each idle arm never closes and keeps out of the area."""
    p = node["intent"]["params"]
    done = marks.get("completion", 0)
    working = list(dict.fromkeys(p["arms"]))
    for name in working:
        arm = arm_index(name)
        home = rec.ee[0, arm]
        arrived = P.first_stay(P.within(rec.ee[:, arm], home, p["home_radius"]), done,
                               p["frames"])
        if arrived is None:
            return Outcome(False, False, None, f"the {name} arm did not come home and stay "
                           f"(within {_cm(p['home_radius'])} for {p['frames']} frames)")
        if arrived - done > p["deadline_frames"]:
            return Outcome(False, False, arrived, f"the {name} arm came home {arrived - done} "
                           f"frames after finishing (limit {p['deadline_frames']})")
        away = np.linalg.norm(rec.ee[arrived:, arm] - home, axis=1)
        if away.max() > p["leave_radius"]:
            frame = arrived + int(np.argmax(away > p["leave_radius"]))
            return Outcome(False, False, frame, f"the {name} arm left home again at frame "
                           f"{frame} ({_cm(float(away.max()))} away)")
        again = P.first(rec.closes(arm, p["close"]), done + 1)
        if again is not None:
            return Outcome(False, False, again, f"the {name} arm closed its gripper again at "
                           f"frame {again}")
    for name in (a for a in ARMS if a not in working):
        arm = arm_index(name)
        closed = P.first(rec.closes(arm, p["close"]))
        if closed is not None:
            return Outcome(False, False, closed, f"the idle {name} arm closed its gripper at "
                           f"frame {closed}")
        entered = P.first_true(P.inside_box(rec.ee[:, arm], p["operation_area"]))
        if entered is not None:
            return Outcome(False, False, entered, f"the idle {name} arm entered the work area "
                           f"at frame {entered}")
    return Outcome(True, True, done, "back home and still" if working else "stayed still")


EVALUATORS = {"nearest_at_first_close": grasp, "push_contact": push_contact,
              "pushed_towards": pushed_towards, "set_down_in_relation": relative_placement,
              "held_above": stack, "lowered_into": bowl, "carried_over": route,
              "final_placement": orientation, "finished": finish}
