"""Behaviour + world -> expert plan: per-arm waypoints in the world frame, gripper events.

Positions are where the gripper's grasp centre (between the fingertips) should be, in metres;
the simulator maps them to its own tool frame. A `home` point has no position: it is the
arm's rest pose. Every action kind is covered: pickups (held at home, as the demonstrations
do), relative placements, stacks, bowls, pushes, transfers with a route and a final yaw,
unstacking, two-arm sequences (each object held until both are up), conditional branches.
"""

from __future__ import annotations

import math
from typing import Literal

from robofollow.compiler.planning.routes import passes_over
from robofollow.compiler.scene.behaviour import Behaviour, Step
from robofollow.compiler.scene.model import Model
from robofollow.compiler.scene.world import DIRECTIONS, RELATION_RANGE, World, in_cone

PRE_GRASP = 0.08  # m: approach height above the grasp point
LIFT = 0.10  # m: lift after grasping
PRE_PLACE = 0.06  # m: approach height above the place point
RETREAT = 0.08  # m: move up after releasing
PLACE_GAP = 0.04  # m: free space between a placed object and its landmark
PLACE_CLEARANCE = 0.01  # m: free space kept between a placed object and any other body
# (further out, sideways) shifts (m) tried in order when the nominal place spot is taken
PLACE_SHIFTS = ((0.0, 0.0), (0.015, 0.0), (0.0, 0.02), (0.0, -0.02), (0.03, 0.0),
                (0.015, 0.025), (0.015, -0.025), (0.0, 0.04), (0.0, -0.04), (0.045, 0.0),
                (0.0, 0.055), (0.0, -0.055), (0.02, 0.06), (0.02, -0.06))
STACK_CLEARANCE = 0.005  # m: release height above the support's top
TABLE_CLEARANCE = 0.001  # m: release height above the table
ROUTE_CLEARANCE = 0.09  # m: carried object's bottom above the highest body on the route
PUSH_FACE = 0.012  # m: the closed fingers' half-depth along the push (their face to centre)
PUSH_RUN_UP = 0.035  # m: start this far back from touching the object
PUSH_TRAVEL = 0.03  # m: how far the fingers carry the object past first touching it
PUSH_SPEED = 0.05  # m/s: slow enough that the object moves with the fingers, stops with them
PUSH_BACK_OFF = 0.03  # m: back off after pushing
PUSH_HEIGHT = 0.02  # m: fingertip height above the table while pushing
OPEN, CLOSED = 1.0, 0.0


class PlanPoint(Model):
    name: str
    arm: Literal["left", "right"]
    position: tuple[float, float, float] | None  # None for `home`
    yaw_degrees: float = 0.0  # gripper rotation about z from its top-down grasp
    gripper: float  # target opening at this point: 1 open, 0 closed
    speed: float | None = None  # m/s: how fast to come here (None: the executor's own)


class Plan(Model):
    points: tuple[PlanPoint, ...]

    def of(self, arm: str) -> list[PlanPoint]:
        return [p for p in self.points if p.arm == arm]


def _up(position: tuple[float, float, float], dz: float) -> tuple[float, float, float]:
    return (position[0], position[1], position[2] + dz)


class _Planner:
    def __init__(self, world: World):
        self.world = world
        self.points: list[PlanPoint] = []

    def add(self, name: str, arm: str, position, gripper: float, yaw: float = 0.0,
            speed: float | None = None) -> None:
        if position is not None:
            position = tuple(round(v, 6) for v in position)
        self.points.append(PlanPoint(name=name, arm=arm, position=position, gripper=gripper,
                                     yaw_degrees=yaw, speed=speed))

    def grasp_point(self, body: str) -> tuple[float, float, float]:
        pose = self.world.poses[body]
        return (pose.x, pose.y, pose.z)

    def pick(self, step: Step) -> tuple[float, float, float]:
        grasp = self.grasp_point(step.source)
        self.add("pre_grasp", step.arm, _up(grasp, PRE_GRASP), OPEN)
        self.add("grasp", step.arm, grasp, OPEN)
        self.add("close", step.arm, grasp, CLOSED)
        lifted = _up(grasp, LIFT)
        self.add("lift", step.arm, lifted, CLOSED)
        return lifted

    def route(self, step: Step, start: tuple[float, float, float]) -> None:
        over = passes_over(step, self.world)
        if not over:
            return
        carried = self.world.bodies[step.source].half_extents[2]
        height = max(self.world.top(b) for b in over) + ROUTE_CLEARANCE + carried
        for body in sorted(over, key=lambda b: math.dist(start[:2], (self.world.poses[b].x,
                                                                    self.world.poses[b].y))):
            pose = self.world.poses[body]
            self.add("via", step.arm, (pose.x, pose.y, max(height, start[2])), CLOSED)

    def place(self, step: Step) -> None:
        lifted = self.pick(step)
        self.route(step, lifted)
        point = place_spot(self.world, step)[0]
        yaw = step.yaw_degrees or 0.0
        self.add("pre_place", step.arm, _up(point, PRE_PLACE), CLOSED, yaw)
        self.add("place", step.arm, point, CLOSED, yaw)
        self.add("release", step.arm, point, OPEN, yaw)
        self.add("retreat", step.arm, _up(point, RETREAT), OPEN, yaw)
        self.add("home", step.arm, None, OPEN)

    def push(self, step: Step) -> None:
        source, target = self.world.poses[step.source], self.world.poses[step.target]
        self.points += push_points(self.world, step.arm, step.source,
                                   (target.x - source.x, target.y - source.y))


def place_spot(world: World, step: Step) -> tuple[tuple[float, float, float], bool]:
    """Where a place step releases its object, and whether that spot is free: on or in the
    target, or beside it in the relation's direction, at the first of PLACE_SHIFTS that keeps
    PLACE_CLEARANCE from every other body and still stands in the relation (else the nominal
    spot, not free)."""
    half = world.bodies[step.source].half_extents
    target = world.poses[step.target]
    if step.relation == "on":
        return (target.x, target.y, world.top(step.target) + half[2] + STACK_CLEARANCE), True
    if step.relation == "in":
        return (target.x, target.y, world.bottom(step.target) + 0.005 + half[2] + 0.01), True
    direction = DIRECTIONS.get(step.relation, (1.0, 0.0))  # next_to: to the right
    landmark = world.bodies[step.target].half_extents
    reach = (abs(direction[0]) * (landmark[0] + half[0]) +
             abs(direction[1]) * (landmark[1] + half[1]) + PLACE_GAP)
    spots = [(target.x + direction[0] * (reach + out) - direction[1] * side,
              target.y + direction[1] * (reach + out) + direction[0] * side)
             for out, side in PLACE_SHIFTS]
    free = [spot for spot in spots if _free(world, spot, step.source)
            and in_cone(spot[0] - target.x, spot[1] - target.y, direction)
            and math.dist(spot, (target.x, target.y)) <= RELATION_RANGE]
    x, y = (free or spots)[0]
    return (x, y, world.table + half[2] + TABLE_CLEARANCE), bool(free)


def _free(world: World, spot: tuple[float, float], source: str) -> bool:
    """Whether `source` set down at `spot` keeps PLACE_CLEARANCE from every other body."""
    half = world.bodies[source].half_extents
    for body, pose in world.poses.items():
        other = world.bodies[body].half_extents
        if body != source and (abs(spot[0] - pose.x) < half[0] + other[0] + PLACE_CLEARANCE
                               and abs(spot[1] - pose.y) < half[1] + other[1] + PLACE_CLEARANCE):
            return False
    return True


def push_points(world: World, arm: str, body: str,
                direction: tuple[float, float]) -> list[PlanPoint]:
    """Pushing `body` along a planar direction: close the gripper above a run-up, lower it
    behind the body, carry the body PUSH_TRAVEL past first touching it at PUSH_SPEED, back
    off, lift, go home (gripper closed)."""
    planner = _Planner(world)
    length = math.hypot(*direction) or 1.0
    ux, uy = direction[0] / length, direction[1] / length
    pose, half = world.poses[body], world.bodies[body].half_extents
    round_ = world.bodies[body].kind in ("sphere", "cylinder")
    extent = half[0] if round_ else abs(ux) * half[0] + abs(uy) * half[1]  # centre to face
    touch = extent + PUSH_FACE  # grasp centre to object centre when the fingers touch it
    z = world.table + PUSH_HEIGHT
    start = (pose.x - ux * (touch + PUSH_RUN_UP), pose.y - uy * (touch + PUSH_RUN_UP), z)
    end = (pose.x - ux * (touch - PUSH_TRAVEL), pose.y - uy * (touch - PUSH_TRAVEL), z)
    # the closed fingers' wide face (normal along the gripper's z axis) meets the object
    yaw = (math.degrees(math.atan2(uy, ux)) + 90.0 + 90.0) % 180.0 - 90.0
    planner.add("pre_push", arm, _up(start, LIFT), OPEN, yaw)
    planner.add("close", arm, _up(start, LIFT), CLOSED, yaw)
    planner.add("push_start", arm, start, CLOSED, yaw)
    planner.add("push_end", arm, end, CLOSED, yaw, speed=PUSH_SPEED)
    backed = (end[0] - ux * PUSH_BACK_OFF, end[1] - uy * PUSH_BACK_OFF, z)
    planner.add("back_off", arm, backed, CLOSED, yaw)
    planner.add("lift", arm, _up(backed, LIFT), CLOSED, yaw)
    planner.add("home", arm, None, CLOSED)
    return planner.points


def plan(behaviour: Behaviour, world: World) -> Plan:
    """The expert's plan for a behaviour in a world (its selected branch, for a conditional)."""
    planner = _Planner(world)
    held = []
    for step in behaviour.steps:
        if step.action == "pick":
            planner.pick(step)
            held.append(step.arm)  # held until every step is done, then carried home
        elif step.action == "push":
            planner.push(step)
        else:
            planner.place(step)
    for arm in held:
        planner.add("home", arm, None, CLOSED)
    return Plan(points=tuple(planner.points))
