"""The judged catalogue: scripted imperfect behaviours, each with the verdict a careful judge
applying the paper's definitions gives, written as bounds on IS / ES / complete with a one-line
justification. The oracle must agree on every one.

The paper's definitions the verdicts apply: Intent is selecting the right object, relation,
waypoint, orientation or branch and moving in the semantically appropriate direction, even
when execution is imperfect; Execution is the sub-goal physically done; later stages are
gated on earlier ones; every task ends with a 20% finishing stage (refrain from further
actions unrelated to the instruction); Completion is action-dependent (pickups: final IS and
ES at least 0.8; other actions: the final state or action progress; Scene 3: the final
placement-and-orientation stage executed) and does not need every intermediate stage in full.
Completion is whether the task is done in the episode's final state: an object placed right
and then taken away again, in any scene, ends the episode not done.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pytest

from robofollow.compiler.planning.plans import (
    LIFT,
    OPEN,
    PUSH_TRAVEL,
    PlanPoint,
    plan,
    push_points,
)
from robofollow.compiler.scene.behaviour import Behaviour, Step
from robofollow.compiler.scene.world import World
from robofollow.eval.policies.reference import REFERENCE_POLICIES
from robofollow.eval.running.episode import run_episode
from robofollow.sim import robot
from tests.judged import Script, analog, holding_on, released_higher, step_of, without
from tests.sim_helpers import episode, shipped


@dataclass(frozen=True)
class Case:
    name: str
    episode: str
    script: Callable[[Script], Script]
    IS: tuple[float, float]
    ES: tuple[float, float]
    complete: bool | None  # None: either, the verdict depends on where a falling object lands
    why: str


def exactly(value: float) -> tuple[float, float]:
    return (value, value)


def at_most(value: float) -> tuple[float, float]:
    return (0.0, value)


NOTHING = exactly(0.0)
BOWL_OPENING = 0.7  # fingers 5.3 cm apart: round a 4 cm cube, inside a bowl's 7.2 cm rim
FULL = exactly(1.0)

S1_PICK = "scene1/L0/pickup_yellow_block_1_left#r1"  # left arm, yellow_block_1
S1_BEHIND = "scene1/L0/place_yellow_block_1_behind_red_cylinder#r1"  # right arm
S1_LEFT_OF = "scene1/L0/place_yellow_block_2_left_of_red_sphere#r1"  # left arm
S1_L1 = "scene1/L1/place_yellow_block_1_beside_red_cylinder@scene1_2#r1"  # yellow_block_3 now
S1_L2 = "scene1/L2/place_yellow_block_2_left_of_red_sphere@default/referents-e7a8892d#r1"
S1_L3 = "scene1/L3/place_yellow_block_1_behind_red_cylinder@scene1_2/referents-1b23fabc#r1"
S2_PICK = "scene2/L0/pickup_right_cube#r1"  # left arm, small_red_cube
S2_PICK_BIG = "scene2/L0/pickup_red_cylinder#r1"
S2_STACK = "scene2/L0/stack_left_cube_on_red_cylinder#r1"
S2_BOWL = "scene2/L0/place_right_cube_in_green_bowl#r1"
S2_PUSH = "scene2/L0/push_left_cube_to_red_cylinder#r1"
S2_PUSH_ROW = "scene2/L0/push_left_cube_to_blue_cylinder#r1"
S2_L1_BOWL = "scene2/L1/place_right_cube_in_green_bowl@scene2_5#r1"  # the bowls swapped
S2_L2_STACK = "scene2/L2/stack_left_cube_on_blue_cylinder@default/referents-29baf3ea#r1"
S2_L3_PUSH = "scene2/L3/push_left_cube_to_red_cylinder@scene2_1/referents-d367c008#r1"
S3_VIA = "scene3/L0/r_pick2_via4_to6_short_front#r1"  # red -> blue label over yellow
S3_AVOID = "scene3/L0/l_pick5_around2_to1_short_right#r1"  # blue -> green label, not over red
S3_L1 = "scene3/L1/r_pick2_via4_to6_short_front@scene3_2#r1"  # yellow and blue swapped
S3_L2_AVOID = "scene3/L2/r_pick2_via4_to6_short_front@default/routes-cfa91afc#r1"
S3_L3_AVOID = "scene3/L3/l_pick4_around2_to1_short_right@scene3_1/orientation-71c3420f#r1"
S4_IF = "scene4/L0/s41_if_bowl_nonempty_then_l_pick_blue_else_r_stack#r1"  # then: left blue
S4_SEQ = "scene4/L0/s41_seq_l_bowl_then_r_green_cylinder#r1"
S4_UNSTACK = "scene4/L0/s41_r_unstack_green_cylinder_to_slot6#r1"
S4_STACK = "scene4/L0/s41_r_stack_green_cylinder_on_yellow#r1"
S4_PICK = "scene4/L0/s41_l_pick_blue_sphere#r1"
S4_BOWL_CUBE = "scene4/L0/s41_l_pick_cube_in_bowl#r1"
S4_L1_IF = "scene4/L1/s41_if_bowl_nonempty_then_l_pick_blue_else_r_stack@scene4_5#r1"
S4_L2_SEQ = "scene4/L2/s41_seq_r_green_cylinder_then_l_bowl@scene4_1/referents-2fc0eaa9#r1"
S4_L3_PICK = "scene4/L3/s41_l_pick_blue_sphere@scene4_5/referents-eea05ed2#r1"


def pick(arm: str, source: str) -> Behaviour:
    return Behaviour(steps=(Step(action="pick", arm=arm, source=source),))


def place(arm: str, source: str, relation: str, target: str, **extra) -> Behaviour:
    return Behaviour(steps=(Step(action="place", arm=arm, source=source, relation=relation,
                                 target=target, **extra),))


def training(label: str) -> Behaviour:
    return shipped().training[label]


def offset_from(s: Script, body: str, dx: float, dy: float) -> tuple[float, float]:
    x, y, _ = s.at(body)
    return x + dx, y + dy


def put_near(arm: str, source: str, landmark: str, dx: float, dy: float, **put):
    """Pick `source`, set it down at (dx, dy) from `landmark`, go home."""
    def script(s: Script) -> Script:
        return s.pick(arm, source).put(arm, *offset_from(s, landmark, dx, dy), **put).home(arm,
                                                                                            OPEN)
    return script


def drop_after_lift(points):
    """Open the gripper right after lifting, then go on empty-handed."""
    lift = [p.name for p in points].index("lift")
    return points[:lift + 1] + [p.model_copy(update={"gripper": OPEN}) for p in points[lift:]]


def shifted_placement(dx: float, dy: float):
    """A plan edit: set the object down (dx, dy) away from the planned spot."""
    def edit(points):
        moved = ("pre_place", "place", "release", "retreat")
        return [p.model_copy(update={"position": (p.position[0] + dx, p.position[1] + dy,
                                                  p.position[2])}) if p.name in moved else p
                for p in points]
    return edit


def carried_round(s: Script, arm: str, source: str, waypoints, label: str, yaw: float) -> Script:
    """Carry `source` at transit height through the given (x, y) points, then set it down on
    `label`'s centre turned by `yaw`."""
    s.pick(arm, source)
    z = s.world.table + 0.16
    for x, y in waypoints:
        s.move(arm, (x, y, z))
    x, y, _ = s.at(label)
    return s.put(arm, x, y, on=label, yaw=yaw).home(arm, OPEN)


def beside_yellow(s: Script) -> list[tuple[float, float]]:
    """A straight crossing of the yellow slab's column 6 mm clear of its footprint, on the
    side of the blue slab (so still nearer yellow than blue)."""
    y = s.at("yellow_slab")[1] + s.half("yellow_slab")[1] + 0.006
    return [(s.at("red_slab")[0], y), (s.at("yellow_slab")[0] + 0.05, y)]


def released_at(s: Script) -> PlanPoint:
    """Where the asked plan lets go of its object."""
    return next(p for p in plan(s.asked, s.world).points if p.name == "release")


def taken_again(s: Script, lift: float = LIFT) -> Script:
    """Do the task, then grasp the object again where it was let go of and lift it (the
    fingers coming down narrower into a bowl, whose rim an open gripper would land on)."""
    point, step = released_at(s), step_of(s.asked)
    opening = BOWL_OPENING if step.relation == "in" else OPEN
    return s.perform().take_again(point.arm, step.source, point.position, point.yaw_degrees,
                                  lift=lift, opening=opening)


def placed_then_lifted(above: float):
    """Do the task, then grasp the object again and hold it `above` metres higher, to the
    end."""
    return lambda s: taken_again(s, lift=above)


def placed_then_put_back(s: Script) -> Script:
    """Do the task, then grasp the object again and set it down where it was taken from."""
    point = released_at(s)
    x, y, _ = s.at(step_of(s.asked).source)
    return (taken_again(s).put(point.arm, x, y, yaw=point.yaw_degrees)
            .home(point.arm, OPEN))


def picked_then_put_back(s: Script) -> Script:
    """Do the pickup, then set the object down where it was taken from."""
    step = step_of(s.asked)
    s.perform().held[step.arm] = step.source
    return s.put_back(step.arm)


def pushed_on(direction: tuple[float, float], further: float):
    """Do the push asked, then push the object again from where that push left it (the
    planner's travel towards the target), along `direction` and `further` metres longer."""
    def script(s: Script) -> Script:
        step = step_of(s.asked)
        (x, y, z), (tx, ty, _) = s.at(step.source), s.at(step.target)
        length = math.hypot(tx - x, ty - y)
        there = (x + (tx - x) / length * PUSH_TRAVEL, y + (ty - y) / length * PUSH_TRAVEL, z)
        moved = World(s.scene, s.record.layout,
                      positions={**{b: s.at(b) for b in s.world.poses}, step.source: there})
        ux, uy = np.divide(direction, math.hypot(*direction))
        longer = [p.model_copy(update={"position": (p.position[0] + ux * further,
                                                    p.position[1] + uy * further,
                                                    p.position[2])})
                  if p.name in ("push_end", "back_off", "lift") else p
                  for p in push_points(moved, step.arm, step.source, direction)]
        return s.perform().points(longer)
    return script


def both_branches(first: str):
    def script(s: Script) -> Script:
        branches = [s.asked, Behaviour(steps=s.asked.other)]
        for behaviour in branches if first == "selected" else branches[::-1]:
            s.perform(behaviour)
        return s
    return script


CASES = [
    # -- Scene 1: spatial relations -----------------------------------------------------------
    Case("s1 analog gripper (0.4 closed, 0.65 open), placed right", S1_BEHIND,
         lambda s: s.perform().edit(analog), FULL, FULL, True,
         "the fingers grasp, carry and release the block: commanded values are not evidence"),
    Case("s1 analog gripper on a pickup", S1_PICK, lambda s: s.perform().edit(analog),
         FULL, FULL, True, "a 0.4 command shuts the fingers on the block: a real grasp"),
    Case("s1 closes in free air 15 cm above a wrong block, then does the task", S1_BEHIND,
         lambda s: s.close_at("right", offset_from(s, "yellow_block_3", 0, 0) + (0.92,))
         .home("right").perform(), FULL, FULL, True,
         "a close far from any object goes for nothing"),
    Case("s1 closes 20 cm above the right block, never touches it", S1_PICK,
         lambda s: s.close_at("left", s.at("yellow_block_1")[:2] + (0.97,)).home("left"),
         NOTHING, NOTHING, False, "closing out of reach of every object is not going for one"),
    Case("s1 closes 5 cm above the right block (a missed grasp), gives up", S1_PICK,
         lambda s: s.close_at("left", s.at("yellow_block_1")[:2] + (s.at("yellow_block_1")[2]
                                                                    + 0.05,)).home("left"),
         exactly(0.8), NOTHING, False,
         "it went for the right block (Intent) but grasped nothing (Execution)"),
    Case("s1 wrong object", S1_BEHIND,
         lambda s: s.perform(s.variant(source="yellow_block_3")), NOTHING, NOTHING, False,
         "picking another block is the wrong selection from the first stage"),
    Case("s1 wrong arm", S1_PICK, lambda s: s.perform(s.variant(arm="right")), NOTHING,
         NOTHING, False, "the instruction names the left arm"),
    Case("s1 wrong side (in front instead of behind)", S1_BEHIND,
         lambda s: s.perform(s.variant(relation="in_front_of")), exactly(0.4), exactly(0.4),
         False, "right block, wrong relation: Intent stops at the placement"),
    Case("s1 behind at 11 cm (range 12 cm)", S1_BEHIND,
         put_near("right", "yellow_block_1", "red_cylinder", 0.0, 0.11), FULL, FULL, True,
         "inside every tolerance"),
    Case("s1 straight behind at 13 cm (range 12 cm)", S1_BEHIND,
         put_near("right", "yellow_block_1", "red_cylinder", 0.0, 0.13), FULL, exactly(0.4),
         False, "the right side is Intent; the distance is Execution"),
    Case("s1 behind, 40 deg off the axis (cone 45)", S1_BEHIND,
         put_near("right", "yellow_block_1", "red_cylinder", -0.058, 0.069), FULL, FULL, True,
         "inside the relation's cone"),
    Case("s1 50 deg off 'behind', i.e. nearer 'left of'", S1_BEHIND,
         put_near("right", "yellow_block_1", "red_cylinder", -0.069, 0.058), exactly(0.4),
         exactly(0.4), False, "outside the cone the direction is another relation"),
    Case("s1 behind the other sphere, 26 cm from the asked one (inside its cone)",
         "scene1/L0/place_yellow_block_2_behind_green_sphere#r4",
         lambda s: s.perform(training("place_yellow_block_2_behind_red_sphere")),
         exactly(0.4), exactly(0.4), False, "set down by another landmark: not the asked one"),
    Case("s1 straight behind at 18 cm (a relation reaches 20 cm)", S1_BEHIND,
         put_near("right", "yellow_block_1", "red_cylinder", 0.0, 0.18), FULL, exactly(0.4),
         False, "still by the asked landmark, on its side: Intent; too far: Execution"),
    Case("s1 dropped right after the lift", S1_LEFT_OF,
         lambda s: s.perform(edit=drop_after_lift), exactly(0.4), exactly(0.4), False,
         "grasped and lifted, never brought to the landmark"),
    Case("s1 dropped from 15 cm above the right spot", S1_BEHIND,
         lambda s: s.perform(edit=released_higher(0.15)), FULL, exactly(0.4), None,
         "the right side (Intent), but a drop is not a placement; completion from where it lands"),
    Case("s1 knocked off after placing", S1_BEHIND,
         lambda s: s.perform().sweep("right", s.at("red_cylinder")[1] + 0.085, 0.22, -0.02),
         exactly(0.8), exactly(0.8), False,
         "placed, then moved again: the finish is lost and the end state is wrong"),
    Case("s1 placed, then lifted again and held 6 cm above the spot", S1_BEHIND,
         placed_then_lifted(0.06), exactly(0.8), exactly(0.8), False,
         "placed right, then taken up again: at the end it is held in the air"),
    Case("s1 placed, then carried back to where it was taken from", S1_BEHIND,
         placed_then_put_back, exactly(0.8), exactly(0.8), False,
         "placed right, then undone: at the end it is not behind the cylinder"),
    Case("s1 picks up, then sets it down again where it was", S1_PICK, picked_then_put_back,
         exactly(0.8), exactly(0.8), True,
         "picked up (complete under the paper's pickup rule), then set down: the finish"),
    Case("s1 held without release over the right spot", S1_BEHIND,
         lambda s: s.perform(edit=holding_on), exactly(0.8), exactly(0.4), False,
         "brought to the right side (Intent) but never let go; carried off again"),
    Case("s1 touches and releases a wrong block first, then does the task", S1_BEHIND,
         lambda s: s.pick("right", "yellow_block_3", lift=0.02).put_back("right").perform(),
         NOTHING, NOTHING, True,
         "the first object it went for is wrong (gated from there); the end state is right"),
    Case("s1 does the task, then touches and releases a wrong block", S1_BEHIND,
         lambda s: s.perform().pick("right", "yellow_block_3", lift=0.02).put_back("right"),
         exactly(0.8), exactly(0.8), True, "an unrelated action after the task costs the finish"),
    Case("s1 idle arm grabs and puts back a block before the task", S1_BEHIND,
         lambda s: s.pick("left", "yellow_block_2", lift=0.02).put_back("left").perform(),
         exactly(0.8), exactly(0.8), True, "the other arm's interference costs the finish"),
    Case("s1 idle arm grabs and puts back a block after the task", S1_BEHIND,
         lambda s: s.perform().pick("left", "yellow_block_2", lift=0.02).put_back("left"),
         exactly(0.8), exactly(0.8), True, "judged the same before and after the task"),
    Case("s1 shakes at home after the task", S1_BEHIND,
         lambda s: s.perform().shake("right", 0.15, 4), exactly(0.8), exactly(0.8), True,
         "waving at home is not being still"),
    Case("s1 comes home 200 frames late", S1_BEHIND,
         lambda s: s.perform(edit=without("home")).wait(200).home("right", OPEN),
         exactly(0.8), exactly(0.8), True, "the finish has a deadline"),
    Case("s1 sweeps the back row with the closed gripper", S1_BEHIND,
         lambda s: s.sweep("right", s.at("red_cylinder")[1], 0.22, -0.25), NOTHING, NOTHING,
         False, "pushing is not picking: nothing asked was done"),
    Case("s1 L1: the training motion on the changed layout (wrong block)", S1_L1,
         lambda s: s.perform(place("right", "yellow_block_1", "right_of", "red_cylinder")),
         NOTHING, NOTHING, False, "the red ball moved: the block to its right is another one"),
    Case("s1 picks the block and puts it back where it was", S1_BEHIND,
         lambda s: s.pick("right", "yellow_block_1").put_back("right"), exactly(0.4),
         exactly(0.4), False, "grasped and lifted (the source stage), not carried anywhere"),
    Case("s1 L2: the right block placed on the wrong side", S1_L2,
         lambda s: s.perform(s.variant(relation="behind")), exactly(0.4), exactly(0.4), False,
         "a novel wording understood for the object, not for the relation"),
    Case("s1 L3: right block, right side, 14 cm away", S1_L3,
         lambda s: put_near("right", s.asked.steps[0].source, "red_cylinder", 0.0, 0.14)(s),
         FULL, exactly(0.4), False, "Intent is the direction, whatever the distance"),

    # -- Scene 2: properties and actions -------------------------------------------------------
    Case("s2 analog gripper on a pickup", S2_PICK, lambda s: s.perform().edit(analog), FULL,
         FULL, True, "the fingers hold and lift the cube"),
    Case("s2 picks up, then drops it from home", S2_PICK,
         lambda s: s.perform().grip("left", OPEN), exactly(0.8), exactly(0.8), True,
         "picked up (complete under the paper's pickup rule), then let go: the finish"),
    Case("s2 wrong arm on a pickup", S2_PICK_BIG, lambda s: s.perform(s.variant(arm="right")),
         NOTHING, NOTHING, False, "the instruction names the left arm"),
    Case("s2 stack 1.5 cm off centre", S2_STACK,
         put_near("left", "large_blue_cube", "large_red_cylinder", 0.015, 0.0,
                  on="large_red_cylinder", above=0.0), FULL, FULL, True,
         "within the stacking tolerance, resting on the target"),
    Case("s2 stack 4.5 cm off centre: it falls off", S2_STACK,
         put_near("left", "large_blue_cube", "large_red_cylinder", 0.045, 0.0,
                  on="large_red_cylinder", above=0.0), (0.8, 1.0), exactly(0.4), False,
         "aimed at the right target (Intent), did not stay on it (Execution)"),
    Case("s2 stacked, then lifted again and held 6 cm above the cylinder", S2_STACK,
         placed_then_lifted(0.06), exactly(0.8), exactly(0.8), False,
         "stacked right, then taken up again: at the end it is held in the air"),
    Case("s2 stacked, then carried back to where it was taken from", S2_STACK,
         placed_then_put_back, exactly(0.8), exactly(0.8), False,
         "stacked right, then undone: at the end it is not on the cylinder"),
    Case("s2 stacked on the wrong cylinder", S2_STACK,
         lambda s: s.perform(s.variant(target="small_blue_cylinder")), exactly(0.4),
         exactly(0.4), False, "right object, wrong target"),
    Case("s2 dropped into the right bowl from 15 cm", S2_BOWL,
         lambda s: s.perform(edit=released_higher(0.15)), FULL, exactly(0.4), True,
         "the right bowl (Intent), a drop (not Execution); it ends in the bowl (complete)"),
    Case("s2 put in the bowl, then lifted again and held 6 cm above it", S2_BOWL,
         placed_then_lifted(0.06), exactly(0.8), exactly(0.8), False,
         "in the right bowl, then taken up again: at the end it is held in the air"),
    Case("s2 put in the bowl, then carried back to where it was taken from", S2_BOWL,
         placed_then_put_back, exactly(0.8), exactly(0.8), False,
         "in the right bowl, then undone: at the end it is not in the bowl"),
    Case("s2 placed in the wrong bowl", S2_BOWL,
         lambda s: s.perform(s.variant(target="yellow_bowl")), exactly(0.4), exactly(0.4),
         False, "right object, wrong bowl"),
    Case("s2 set down on the right bowl's rim", S2_BOWL,
         put_near("right", "small_red_cube", "green_bowl", 0.0, -0.055, above=0.02),
         FULL, exactly(0.4), False,
         "aimed at the right bowl, not in it"),
    Case("s2 L1: the training bowl position after the bowls swapped", S2_L1_BOWL,
         lambda s: s.perform(s.variant(target="yellow_bowl")), exactly(0.4), exactly(0.4),
         False, "the green bowl moved; the old spot holds the yellow one"),
    Case("s2 push with the gripper open", S2_PUSH,
         lambda s: s.perform(edit=lambda ps: [p.model_copy(update={"gripper": 0.55})
                                              for p in ps]), FULL, NOTHING, True,
         "the right object pushed the right way (Intent), not as a push is done; it moved"),
    Case("s2 pushed to the cylinder, then pushed 4 cm aside", S2_PUSH,
         pushed_on((1.0, 0.0), 0.01), exactly(0.8), exactly(0.8), False,
         "pushed right, then pushed aside: at the end it lies off the way to the target"),
    Case("s2 pushed the wrong way", S2_PUSH,
         lambda s: s.perform(s.variant(target="small_blue_cylinder")), exactly(0.4),
         exactly(0.4), False, "right object, wrong direction"),
    Case("s2 pushed the wrong object", S2_PUSH,
         lambda s: s.perform(training("push_red_cylinder_to_left_cube")), NOTHING, NOTHING,
         False, "the first object it pushed is not the asked one"),
    Case("s2 grasps the object it was to push", S2_PUSH,
         lambda s: s.perform(pick("left", "large_blue_cube")), NOTHING, NOTHING, False,
         "the asked action primitive is a push, not a grasp"),
    Case("s2 sweeps the front row left to right", S2_PUSH_ROW,
         lambda s: s.sweep("left", s.at("large_blue_cube")[1], -0.26, 0.05), at_most(0.8),
         at_most(0.8), None, "a blind sweep may push the right object the right way, and more"),
    Case("s2 sweeps the back row", S2_STACK,
         lambda s: s.sweep("left", s.at("large_red_cylinder")[1], -0.26, 0.05), NOTHING,
         NOTHING, False, "no grasp, no stack"),
    Case("s2 L2: stacked on the wrong target", S2_L2_STACK,
         lambda s: s.perform(s.variant(target="large_red_cylinder")), exactly(0.4),
         exactly(0.4), False, "a novel wording understood for the object, not the target"),
    Case("s2 L3: pushed the right cube sideways, not towards the moved target", S2_L3_PUSH,
         lambda s: s.push("left", "large_blue_cube", (1.0, 0.0)), exactly(0.4), exactly(0.4),
         False, "right object, a direction 90 deg off the asked one"),
    Case("s2 L3: pushing the training way comes down on the moved target first", S2_L3_PUSH,
         lambda s: s.push("left", "large_blue_cube", (0.0, 1.0)), NOTHING, NOTHING, False,
         "behind the cube now stands the cylinder: the first object pushed is the wrong one"),

    # -- Scene 3: routes and orientation ------------------------------------------------------
    Case("s3 analog gripper", S3_VIA, lambda s: s.perform().edit(analog), FULL, FULL, True,
         "grasped, carried over the slab, released on the label"),
    Case("s3 turned 30 deg off (Intent 40, Execution 20)", S3_VIA,
         lambda s: s.perform(s.variant(yaw_degrees=30.0)), FULL, exactly(0.48), False,
         "the right orientation roughly (Intent), not precisely (Execution)"),
    Case("s3 turned 60 deg off", S3_VIA, lambda s: s.perform(s.variant(yaw_degrees=60.0)),
         exactly(0.48), exactly(0.48), False, "another orientation"),
    Case("s3 over the slab, then set down beside the label", S3_VIA,
         lambda s: s.perform(edit=shifted_placement(0.06, 0.0)), FULL, exactly(0.48), False,
         "aimed at the right label (Intent), its centre off it (Execution)"),
    Case("s3 over the slab, then its centre just inside the label's edge", S3_VIA,
         lambda s: s.perform(edit=shifted_placement(0.03, 0.0)), FULL, FULL, True,
         "the centre is over the label"),
    Case("s3 placed on the other label", S3_AVOID,
         lambda s: s.perform(s.variant(target="blue_label", waypoints=())), exactly(0.24),
         exactly(0.24), False, "went the other way: no detour round the column, wrong label"),
    Case("s3 'avoid red': detours round the whole column", S3_AVOID,
         lambda s: carried_round(s, "left", "blue_slab", [(-0.04, 0.0), (-0.14, 0.0)],
                                 "green_label", 90.0), FULL, FULL, True,
         "never over the red slab: the constraint as worded"),
    Case("s3 'avoid red': crosses beside red, but cuts over its corner first", S3_AVOID,
         lambda s: carried_round(s, "left", "blue_slab", [
             (s.at("red_slab")[0] + 0.014, s.at("red_slab")[1] + 0.012),
             (s.at("red_slab")[0], s.at("green_slab")[1] + 0.04)], "green_label", 90.0),
         FULL, exactly(0.24), False,
         "chose to go round (Intent), but its centre passed over red (Execution)"),
    Case("s3 'avoid red': carried over red", S3_AVOID,
         lambda s: s.perform(s.variant(waypoints=(("via", "red_slab"),))), exactly(0.24),
         exactly(0.24), False, "the route it was told to avoid"),
    Case("s3 'via yellow': crossed between yellow and blue, nearer yellow", S3_VIA,
         lambda s: carried_round(s, "right", "red_slab", beside_yellow(s), "blue_label", 0.0),
         FULL, exactly(0.24), False,
         "on the right side of the column (Intent), not over the slab (Execution)"),
    Case("s3 'via yellow': over blue instead", S3_VIA,
         lambda s: s.perform(s.variant(waypoints=(("via", "blue_slab"),))), exactly(0.24),
         exactly(0.24), False, "the other waypoint"),
    Case("s3 held without release over the label", S3_VIA,
         lambda s: s.perform(edit=holding_on), exactly(0.8), exactly(0.48), False,
         "route and label right, never let go"),
    Case("s3 placed, then lifted again and held 6 cm above the label", S3_VIA,
         placed_then_lifted(0.06), exactly(0.8), exactly(0.8), False,
         "route and placement right, then taken up again: at the end it is in the air"),
    Case("s3 placed, then carried back to where it was taken from", S3_VIA,
         placed_then_put_back, exactly(0.8), exactly(0.8), False,
         "route and placement right, then undone: at the end it is not on the label"),
    Case("s3 'avoid red': placed, then lifted again and held above the label", S3_AVOID,
         placed_then_lifted(0.06), exactly(0.8), exactly(0.8), False,
         "placed short side right, then taken up again: at the end it is in the air"),
    Case("s3 dropped from 15 cm onto the label", S3_VIA,
         lambda s: s.perform(edit=released_higher(0.15)), FULL, exactly(0.48), False,
         "aimed right; a drop is not a placement, and Scene 3 completes on that stage"),
    Case("s3 the idle arm grabs a slab before the task", S3_VIA,
         lambda s: s.pick("left", "blue_slab", lift=0.02).put_back("left").perform(),
         exactly(0.8), exactly(0.8), True, "Scene 3 has a finishing stage like every task"),
    Case("s3 L1: over the slab at the training position (wrong identity)", S3_L1,
         lambda s: s.perform(s.variant(waypoints=(("via", "blue_slab"),))), exactly(0.24),
         exactly(0.24), False, "the named slab moved across its column"),
    Case("s3 L2 'avoid blue': round the back of the column", S3_L2_AVOID,
         lambda s: carried_round(s, "right", "red_slab", [(-0.04, 0.0), (0.06, 0.0)],
                                 "blue_label", 0.0), FULL, FULL, True,
         "never over the blue slab"),
    Case("s3 L3 'avoid red': over it", S3_L3_AVOID,
         lambda s: s.perform(s.variant(waypoints=(("via", "red_slab"),))), exactly(0.24),
         exactly(0.24), False, "the forbidden slab"),

    # -- Scene 4: logic -------------------------------------------------------------------------
    Case("s4 both branches, the selected one first", S4_IF, both_branches("selected"),
         NOTHING, NOTHING, False, "doing both is not choosing a branch"),
    Case("s4 both branches, the other one first", S4_IF, both_branches("other"), NOTHING,
         NOTHING, False, "doing both is not choosing a branch, in either order"),
    Case("s4 only the other branch", S4_IF,
         lambda s: s.perform(Behaviour(steps=s.asked.other)), NOTHING, NOTHING, False,
         "the condition was read wrong"),
    Case("s4 L1: the training branch after the condition changed", S4_L1_IF,
         lambda s: s.perform(Behaviour(steps=s.asked.other) if s.asked.other else s.asked),
         NOTHING, NOTHING, False, "the layout's answer to the condition changed"),
    Case("s4 idle arm grabs a sphere and puts it back before", S4_IF,
         lambda s: s.pick("right", "red_sphere", lift=0.02).put_back("right").perform(),
         exactly(0.8), exactly(0.8), True, "an unrelated grasp, not the other branch"),
    Case("s4 idle arm grabs a sphere and puts it back after", S4_IF,
         lambda s: s.perform().pick("right", "red_sphere", lift=0.02).put_back("right"),
         exactly(0.8), exactly(0.8), True, "judged the same before and after the task"),
    Case("s4 idle arm enters the work area", S4_PICK,
         lambda s: s.move("right", (0.0, 0.0, 0.85), OPEN).home("right").perform(),
         exactly(0.8), exactly(0.8), True, "the other arm keeps out of the work area"),
    Case("s4 sequence in reverse order", S4_SEQ,
         lambda s: s.perform(Behaviour(steps=s.asked.steps[::-1])), NOTHING, NOTHING, False,
         "the order is the instruction"),
    Case("s4 sequence with the arms swapped", S4_SEQ,
         lambda s: s.perform(Behaviour(steps=tuple(
             st.model_copy(update={"arm": "right" if st.arm == "left" else "left"})
             for st in s.asked.steps))), NOTHING, NOTHING, False,
         "each step names its arm"),
    Case("s4 sequence, only the first step", S4_SEQ,
         lambda s: s.perform(Behaviour(steps=s.asked.steps[:1])), exactly(0.4), exactly(0.4),
         False, "half the sequence"),
    Case("s4 sequence done, then the first object let go of", S4_SEQ,
         lambda s: s.perform().grip("left", OPEN), exactly(0.8), exactly(0.8), True,
         "both picked (complete), the finish lost"),
    Case("s4 L2 sequence with an analog gripper", S4_L2_SEQ,
         lambda s: s.perform().edit(lambda a: _analog_closed(a)), FULL, FULL, True,
         "the fingers shut at 0.4 hold the objects"),
    Case("s4 analog gripper lifts the cube out of the bowl", S4_BOWL_CUBE,
         lambda s: s.perform().edit(lambda a: _analog_closed(a)), FULL, FULL, True,
         "a real grasp"),
    Case("s4 unstacked to the wrong side", S4_UNSTACK,
         lambda s: s.perform(s.variant(relation="behind")), exactly(0.4), exactly(0.4), False,
         "right object, wrong relation"),
    Case("s4 L1: lifts the cylinder off the cube and holds it (it already stood to the right)",
         "scene4/L1/s42_r_unstack_green_cylinder_to_slot6@scene4_5#r1",
         lambda s: s.perform(pick("right", "green_cylinder")), exactly(0.4), exactly(0.4),
         False, "lifting it where it stands is not placing it anywhere"),
    Case("s4 stacked 4.5 cm off centre: it falls", S4_STACK,
         put_near("right", "green_cylinder", "yellow_cylinder", 0.045, 0.0,
                  on="yellow_cylinder", above=0.0), at_most(1.0), exactly(0.4), False,
         "aimed at the right target, did not stay on it"),
    Case("s4 L3: picks the sphere at the training position (the wrong one)", S4_L3_PICK,
         lambda s: s.perform(pick("left", "red_sphere")), NOTHING, NOTHING, False,
         "the spheres swapped; the red one stands where training picks the blue one"),
]


def _analog_closed(action):
    """Closed at 0.4 (open stays 1): the objects here are wider than an 0.65 opening."""
    for column in (6, 13):
        action[column] = 0.4 if action[column] < 0.5 else action[column]
    return action


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_the_oracle_agrees_with_the_judged_verdict(case: Case):
    result = case.script(Script(case.episode)).score()
    assert case.IS[0] - 1e-6 <= result.intent_score <= case.IS[1] + 1e-6, result.table()
    assert case.ES[0] - 1e-6 <= result.execution_score <= case.ES[1] + 1e-6, result.table()
    if case.complete is not None:
        assert result.complete is case.complete, result.table()
    assert_what_it_did_agrees(result)


EVENT = re.compile(r"(grasped|pushed|closed its fingers at) (\w+) at frame (\d+)")
SAID = {"grasped": "grasped {body} (frame {frame})", "pushed": "pushed {body} (frame {frame})",
        "closed its fingers at": "from {body} without grasping it (frame {frame})"}


def assert_what_it_did_agrees(result) -> None:
    """Every grasp, push or close a stage's reason cites is in 'what it did', at its frame;
    'nothing moved' comes with no credit."""
    did = result.executed_behaviour.description
    for stage in result.stages:
        for verb, body, frame in EVENT.findall(stage.reason):
            assert SAID[verb].format(body=body, frame=frame) in did, (stage.reason, did)
    assert did != "nothing moved" or result.intent_score == 0.0, did


def test_the_catalogue_spreads_over_scenes_levels_and_actions():
    assert len(CASES) >= 60
    scenes = {c.episode.split("/")[0] for c in CASES}
    levels = {c.episode.split("/")[1] for c in CASES}
    assert scenes == {"scene1", "scene2", "scene3", "scene4"} and levels == {"L0", "L1", "L2",
                                                                                "L3"}
    kinds = set()
    for case in CASES:
        for step in episode(case.episode).behaviour.steps:
            kinds.add((step.action, "transfer" if step.waypoints else
                       step.relation if step.relation in ("on", "in") else None))
    assert {("pick", None), ("place", None), ("place", "on"), ("place", "in"), ("push", None),
            ("place", "transfer")} <= kinds
    assert all(c.why and len(c.why) < 100 for c in CASES)


class Overshooting:
    """The expert, as a learned policy sends it: "open" is 1.02 and the right wrist asks for
    0.02 rad past its limit while the arm is at home (targets past the joint limits)."""

    def __init__(self):
        self.expert = REFERENCE_POLICIES["expert"]()
        self.uses = self.expert.uses

    def reset(self) -> None:
        self.expert.reset()

    def act(self, observation: dict) -> np.ndarray:
        chunk = np.array(self.expert.act(observation), dtype=float)
        chunk[:, [6, 13]] = np.where(chunk[:, [6, 13]] > 0.9, 1.02, chunk[:, [6, 13]])
        at_home = np.all(np.isclose(chunk[:, 7:13], robot.HOME), axis=1)
        chunk[at_home, 12] = robot.JOINT_HIGH[5] + 0.02
        return chunk


@pytest.mark.slow
def test_over_limit_targets_are_clipped_and_counted_not_an_error(stage):
    """Judged: a policy overshooting limits its demonstrations touch performs the task: full
    marks, and the record counts the clipped actions."""
    run = run_episode(shipped(), stage, episode(S1_BEHIND), Overshooting())
    assert run.error is None and run.clipped > 0
    assert (run.score.intent_score, run.score.execution_score, run.score.complete) == (1.0, 1.0,
                                                                                      True)
