"""The scoring profile: every stage weight and threshold, with units, in one place.

The default follows the paper's definitions (docs/scoring.md lists where it departs from the
paper and the upstream evaluator, and why); a profile is recorded in every goal graph (and so in
every result) it was used for. `STRICT_PROFILE` keeps the stricter completion rule: every stage
but the finish executed in full.
"""

from __future__ import annotations

from typing import Literal

from robofollow.compiler.scene.model import Model
from robofollow.compiler.scene.spec import TABLE_HEIGHT
from robofollow.compiler.scene.world import RELATION_RANGE


class ScoringProfile(Model):
    name: str = "default"
    # stage weights: (source, objective, finish) for one-object actions; pickups fold the
    # objective into the source stage; every task ends with a 20% finishing stage
    pick_weights: tuple[float, float] = (0.8, 0.2)  # source, finish
    action_weights: tuple[float, float, float] = (0.4, 0.4, 0.2)  # source, objective, finish
    transfer_weights: tuple[float, float, float, float] = (0.24, 0.24, 0.32, 0.2)
    #                                                  source, route, outcome, finish
    sequence_weights: tuple[float, float] = (0.8, 0.2)  # shared by the steps, finish
    # completion: "paper" (action-dependent final-state signals) or "strict" (every stage but
    # the finish executed in full)
    completion: Literal["paper", "strict"] = "paper"
    final_frames: int = 10  # frames at the end over which a final state must hold
    pickup_complete: float = 0.8  # a pickup is complete with final IS and ES at least this
    # grasps, read from physics (finger contacts, the measured opening), never the command
    grasp_frames: int = 2  # both fingers on a body this many frames in a row: a grasp
    gripper_span: float = 0.075  # m: the fingers' gap at measured opening 1 (the robot's)
    grip_slack: float = 0.01  # m: a held body is between the fingers: their gap is at least
    #                           its narrowest width less this
    grasp_closing: float = 0.05  # the fingers closed at least this much onto it (opening)
    grasp_window: int = 15  # frames before a grasp in which they were that much wider apart
    grasp_gap: int = 2  # frames a grasp may flicker off and still be the same grasp
    close_threshold: float = 0.35  # measured opening (1 open, 0 closed): shut in free air
    open_threshold: float = 0.7  # measured opening: open (a close goes from open to shut)
    open_frames: int = 5  # frames in a row the fingers stay open to be open (not prised)
    push_close_threshold: float = 0.25  # measured opening: the gripper is closed to push
    reach_radius: float = 0.06  # m: closing this near a body's centre (3-D) goes for it
    support_xy: float = 0.02  # m: a body this close (xy) below another supports it
    support_rise: float = 0.005  # m: and at least this much lower
    min_lift: float = 0.01  # m: lift that counts as picked
    pickup_lift: float = 0.03  # m: lift a single pickup needs
    # pushes: a body starts moving with an arm's gripper on it (or that close, 3-D)
    push_moved: float = 0.005  # m: a body has started moving (xy)
    push_contact_radius: float = 0.08  # m: grasp centre to a body it pushes (3-D)
    push_contact_frames: int = 3  # frames before a body starts moving that the touch may be
    push_height_tolerance: float = 0.12  # m: grasp-centre height to the object's start z
    push_cone_deg: float = 45.0  # deg: pushed within this angle of the source-to-target line
    push_min_intent: float = 0.01  # m: displacement towards the target for intent
    push_min_execution: float = 0.02  # m: and for execution (where it comes to rest)
    # setting down: Intent from where the object was delivered, Execution from where it rests
    aim_radius: float = 0.07  # m: delivered this near (xy) the nearest stack / bowl / label
    set_down_height: float = 0.03  # m: released at most this high above the surface under it
    carry_min: float = 0.03  # m: set down at least this far (xy) from where it was grasped
    rest_tolerance: float = 0.01  # m: bottom within this of a surface: resting on it
    settle_frames: int = 5  # frames an object must keep still to have come to rest
    settle_range: float = 0.002  # m: and move at most this over them
    relation_reach: float = RELATION_RANGE  # m: a placement's side counts this near its
    #                                          landmark (as far as the language's relations reach)
    relation_range: float = 0.12  # m: placement relations hold within this distance
    relation_cone_deg: float = 45.0  # deg: and within this angle of the direction
    stack_xy: float = 0.03  # m: stacked object centred over its target
    stack_clearance: float = 0.005  # m: and its centre at least the half-heights less this above
    bowl_xy: float = 0.04  # m: inside a bowl
    bowl_height: float = 0.06  # m: and below this height over the bowl
    route_x: float = 0.01  # m: a carried object this close (x) to a column crosses it
    route_y: float = 0.06  # m: crossing a 'via' body's column this close (y) to it: its side
    yaw_intent_deg: float = 40.0  # deg: final yaw error for intent
    yaw_execution_deg: float = 20.0  # deg: and for execution
    # finish
    home_radius: float = 0.10  # m: end effector back home
    home_frames: int = 20  # frames it must stay there, still
    still_radius: float = 0.02  # m: still = moving within this over home_frames frames
    home_deadline_frames: int = 180  # after completing the action
    leave_home_radius: float = 0.14  # m: moving this far from home again fails the finish
    stay_tolerance: float = 0.01  # m: a placed (or pushed) object moves at most this after
    disturb_tolerance: float = 0.02  # m: another object moves at most this in the episode
    struck_tolerance: float = 0.03  # m: a push's target, which the pushed object may strike
    topple_deg: float = 45.0  # deg: or tilts at most this (spheres excepted)
    # m: the x, y, z box the idle arm stays out of, z from the table top up 0.26 m, written
    # for a table at the default height (the scorer moves the band with a scene's table)
    operation_area: tuple[tuple[float, float], tuple[float, float], tuple[float, float]] = (
        (-0.20, 0.15), (-0.15, 0.15), (TABLE_HEIGHT, TABLE_HEIGHT + 0.26))


DEFAULT_PROFILE = ScoringProfile()
STRICT_PROFILE = ScoringProfile(name="strict", completion="strict")
