"""Did a trajectory achieve a behaviour? A geometric check of its end state (and, for routes,
of the carried object's path). The stage-wise scorer builds on the same quantities.

Pure numpy over a Trajectory: no MuJoCo.
"""

from __future__ import annotations

import math

import numpy as np

from robofollow.compiler.behaviour import Behaviour, Step
from robofollow.compiler.spec import Scene
from robofollow.compiler.world import World
from robofollow.trajectory import ARMS, Trajectory, yaw

PICK_LIFT = 0.03  # m: a picked object ends at least this far above its start
LIFTED = 0.01  # m: an object this far above its start counts as carried (routes)
ON_TABLE = 0.01  # m: a placed object's bottom within this of the table top
PUSH_DISPLACEMENT = 0.02  # m: a pushed object moves at least this far along the push
PUSH_CONE_DEG = 45.0  # deg: ... within this angle of the source-to-target direction
YAW_TOLERANCE_DEG = 20.0  # deg: final orientation error (modulo 180 deg)


def world_at(trajectory: Trajectory, scene: Scene, frame: int) -> World:
    positions = {b: tuple(p) for b, p in zip(trajectory.bodies, trajectory.positions[frame], strict=True)}
    return World(scene, trajectory.meta["layout"], positions=positions)


def achieved(behaviour: Behaviour, trajectory: Trajectory, scene: Scene) -> tuple[bool, list[str]]:
    """Whether every step of the behaviour holds at the end; failures as one-line reasons."""
    start, end = world_at(trajectory, scene, 0), world_at(trajectory, scene, -1)
    reasons = []
    for step in behaviour.steps:
        reasons += _step_failures(step, trajectory, start, end)
    return not reasons, reasons


def _step_failures(step: Step, trajectory: Trajectory, start: World, end: World) -> list[str]:
    source = step.source
    index = trajectory.index(source)
    held = trajectory.grasped[-1, ARMS.index(step.arm)] == index
    rise = end.poses[source].z - start.poses[source].z
    if step.action == "pick":
        failures = [] if rise >= PICK_LIFT else [f"{source} rose {rise * 100:.1f} cm "
                                                 f"(needs {PICK_LIFT * 100:.0f})"]
        return failures + ([] if held else [f"the {step.arm} arm does not hold {source}"])
    if step.action == "push":
        return _push_failures(step, start, end)
    failures = [] if not held else [f"{source} was not released"]
    if not end.related(source, step.relation, step.target):
        p = end.poses[source]
        failures.append(f"{source} is not {step.relation} {step.target} "
                        f"(ends at {p.x:.3f}, {p.y:.3f}, {p.z:.3f})")
    elif step.relation not in ("on", "in") and abs(end.bottom(source) - end.table) > ON_TABLE:
        failures.append(f"{source} is not on the table")
    failures += _route_failures(step, trajectory, start)
    if step.yaw_degrees is not None:
        error = _axis_error(float(yaw(trajectory.quaternions[-1, index])), math.radians(step.yaw_degrees))
        if math.degrees(error) > YAW_TOLERANCE_DEG:
            failures.append(f"{source} ends {math.degrees(error):.0f} deg off the asked "
                            f"orientation (tolerance {YAW_TOLERANCE_DEG:.0f})")
    return failures


def _axis_error(angle: float, target: float) -> float:
    """Difference of two axis directions, modulo 180 deg (rad, 0..pi/2)."""
    error = (angle - target) % math.pi
    return min(error, math.pi - error)


def _push_failures(step: Step, start: World, end: World) -> list[str]:
    s0, t0, s1 = start.poses[step.source], start.poses[step.target], end.poses[step.source]
    direction = np.array([t0.x - s0.x, t0.y - s0.y])
    direction /= np.linalg.norm(direction)
    moved = np.array([s1.x - s0.x, s1.y - s0.y])
    along = float(moved @ direction)
    distance = float(np.linalg.norm(moved))
    if along < PUSH_DISPLACEMENT or along < distance * math.cos(math.radians(PUSH_CONE_DEG)):
        return [f"{step.source} moved {along * 100:.1f} cm towards {step.target} "
                f"({distance * 100:.1f} cm in all; needs {PUSH_DISPLACEMENT * 100:.0f})"]
    return []


def passes_over(trajectory: Trajectory, carried: str, body: str, scene: Scene) -> bool:
    """Whether the carried object's centre is ever over `body`'s footprint while lifted."""
    c, b = trajectory.index(carried), trajectory.index(body)
    lifted = trajectory.positions[:, c, 2] - trajectory.positions[0, c, 2] >= LIFTED
    half = np.array(scene.bodies[body].half_extents[:2])
    offset = np.abs(trajectory.positions[:, c, :2] - trajectory.positions[:, b, :2])
    return bool(np.any(lifted & np.all(offset <= half, axis=1)))


def _route_failures(step: Step, trajectory: Trajectory, start: World) -> list[str]:
    failures = []
    for kind, body in step.waypoints:
        over = passes_over(trajectory, step.source, body, start.scene)
        if kind == "via" and not over:
            failures.append(f"{step.source} never passed over {body}")
        if kind == "avoid" and over:
            failures.append(f"{step.source} passed over {body}")
    return failures
