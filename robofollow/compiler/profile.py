"""The scoring profile: every stage weight and threshold, with units, in one place.

The default reproduces the upstream benchmark's scoring rules; a profile is recorded in every
goal graph (and so in every result) it was used for.
"""

from __future__ import annotations

from robofollow.compiler.model import Model


class ScoringProfile(Model):
    name: str = "default"
    # stage weights: (source, objective, finish) for one-object actions; pickups fold the
    # objective into the source stage
    pick_weights: tuple[float, float] = (0.8, 0.2)  # source, finish
    action_weights: tuple[float, float, float] = (0.4, 0.4, 0.2)  # source, objective, finish
    transfer_weights: tuple[float, float, float] = (0.3, 0.3, 0.4)  # source, route, outcome
    sequence_weights: tuple[float, float] = (0.8, 0.2)  # shared by the steps, finish
    # gripper signal (1 = open, 0 = closed)
    close_threshold: float = 0.35  # a grip closes when the signal falls to this or below
    open_threshold: float = 0.7  # and opens when it rises to this or above
    push_close_threshold: float = 0.25  # the gripper is closed before pushing
    # source grounding
    grasp_radius: float = 0.07  # m: end effector to object (xy) at the first close
    support_xy: float = 0.02  # m: a body this close (xy) below another supports it
    support_rise: float = 0.005  # m: and at least this much lower
    min_lift: float = 0.01  # m: lift that counts as picked
    pickup_lift: float = 0.03  # m: lift a pickup needs (intrinsic-property scene)
    push_contact_radius: float = 0.08  # m: end effector to pushed object (xy)
    push_height_tolerance: float = 0.12  # m: contact height to the object's initial z
    push_moved: float = 0.005  # m: a pushed object has started moving (xy)
    push_cone_deg: float = 45.0  # deg: pushed within this angle of the source-to-target line
    # objectives
    relation_range: float = 0.12  # m: placement relations hold within this distance
    relation_cone_deg: float = 45.0  # deg: and within this angle of the direction
    on_table_tolerance: float = 0.02  # m: back on the table
    stack_xy: float = 0.03  # m: stacked object over its target
    stack_clearance: float = 0.005  # m: and above it
    bowl_xy: float = 0.04  # m: inside a bowl
    bowl_height: float = 0.06  # m: and below this height over the bowl
    push_min_intent: float = 0.01  # m: displacement towards the target for intent
    push_min_execution: float = 0.02  # m: and for execution
    route_x: float = 0.01  # m: carried object over a waypoint, across the path
    route_y: float = 0.06  # m: along the path
    route_clear_y: float = 0.04  # m: away from the other object of the column
    label_edge: float = 0.0695  # m: placed on a square label (centre distance)
    yaw_intent_deg: float = 40.0  # deg: final yaw error for intent
    yaw_execution_deg: float = 20.0  # deg: and for execution
    # finish
    home_radius: float = 0.10  # m: end effector back home
    home_frames: int = 20  # frames it must stay there
    home_deadline_frames: int = 180  # after completing the action
    leave_home_radius: float = 0.14  # m: moving this far from home again fails the finish
    operation_area: tuple[tuple[float, float], tuple[float, float], tuple[float, float]] = (
        (-0.20, 0.15), (-0.15, 0.15), (0.74, 1.0))  # m: x, y, z box the idle arm stays out of


DEFAULT_PROFILE = ScoringProfile()
