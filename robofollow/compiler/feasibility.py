"""Whether the expert can perform a behaviour on a layout, decided from geometry alone (no
physics), before anything is simulated:

- every point of the expert's plan at the nominal positions lies within its arm's reach
  (workspace.py), with room to spare for the layout's largest jitter offset;
- every body to grip fits the open gripper;
- no arm is asked to act while it still holds what an earlier step picked up;
- nothing rests on a body to move;
- a stack goes onto a free, flat top; a relative placement finds a free spot beside its
  landmark.
"""

from __future__ import annotations

import math

from robofollow.compiler import workspace
from robofollow.compiler.behaviour import Behaviour, describe_steps
from robofollow.compiler.plans import place_spot, plan
from robofollow.compiler.world import World

ROLLING = ("sphere",)  # kinds nothing can be stacked on


def infeasible(behaviour: Behaviour, world: World) -> list[str]:
    """Why the expert cannot perform `behaviour` on a layout at its nominal positions (empty:
    it can)."""
    return _holding(behaviour) + _handling(behaviour, world) + _reach(behaviour, world)


def _holding(behaviour: Behaviour) -> list[str]:
    held: dict[str, str] = {}
    problems = []
    for index, step in enumerate(behaviour.steps, start=1):
        if step.arm in held:
            problems.append(f"step {index} ({describe_steps((step,))}) needs the {step.arm} "
                            f"arm, which still holds {held[step.arm]}")
        if step.action == "pick" and step.arm is not None:
            held[step.arm] = step.source
    return problems


def _handling(behaviour: Behaviour, world: World) -> list[str]:
    problems = []
    widest = workspace.GRIPPER_OPENING - workspace.GRIP_CLEARANCE
    for step in behaviour.steps:
        body = world.bodies[step.source]
        covered = world.carried_by(step.source)
        if covered:
            problems.append(f"{', '.join(covered)} rests on {step.source}, the object to move")
        if step.action != "push" and 2 * body.half_extents[0] > widest:
            problems.append(f"{step.source} is {200 * body.half_extents[0]:.1f} cm wide; the "
                            f"open gripper takes at most {100 * widest:.1f} cm")
        if step.action != "place":
            continue
        if step.relation == "on":
            if world.bodies[step.target].kind in ROLLING:
                problems.append(f"nothing stays on {step.target}, a "
                                f"{world.bodies[step.target].kind}")
            others = [b for b in world.carried_by(step.target) if b != step.source]
            if others:
                problems.append(f"{step.target} already carries {', '.join(others)}")
        elif step.relation != "in" and not place_spot(world, step)[1]:
            problems.append(f"no free spot {step.relation.replace('_', ' ')} {step.target} for "
                            f"{step.source}")
    return problems


def _reach(behaviour: Behaviour, world: World) -> list[str]:
    if any(step.arm is None for step in behaviour.steps):
        return []
    scene, slack = world.scene, 0.0
    for body, placed in world.layout.placed.items():
        if placed.support is None:
            jitter = scene.jitter_of(body)
            slack = max(slack, math.hypot(max(map(abs, jitter.x)), max(map(abs, jitter.y))))
    problems = []
    for point in plan(behaviour, world).points:
        if point.position is not None:
            problem = workspace.reach_problem(point.arm, point.position, world.table, slack)
            if problem:
                problems.append(f"{point.name}: {problem}")
    if len(problems) > 1:
        return [f"{problems[0]} (and {len(problems) - 1} more plan point"
                f"{'s' if len(problems) > 2 else ''})"]
    return problems
