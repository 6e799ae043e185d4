"""Route geometry: which bodies a carry passes over, and whether a route constraint means
anything on a layout.

A route is judged against the straight path from the source to the destination (the target's
centre, in the plane). A body named in a route ("pass over W", "avoid X") must be on the way:
between the two, its footprint clear of theirs along the path, and its centre at most
ROUTE_BAND to either side of the path. Otherwise "pass over W" asks for a detour backwards
or far off the way, and "avoid X" is vacuous: a carry straight to the destination never
comes near X.
"""

from __future__ import annotations

import math

from robofollow.compiler.behaviour import Step
from robofollow.compiler.world import World

ROUTE_BAND = 0.08  # m: a route body lies at most this far to either side of the straight path


def passes_over(step: Step, world: World) -> tuple[str, ...]:
    """The bodies the carried object is routed over: each 'via' body, and for 'avoid X' the
    other body on the way in X's column (the detour the words ask for)."""
    over = set()
    for mode, body in step.waypoints:
        if mode == "via":
            over.add(body)
            continue
        over.update(world.column_mates(body, excluding=(step.source, step.target)))
    return tuple(sorted(over))


def _extent(world: World, body: str, ux: float, uy: float) -> float:
    """Half the length of a body's footprint along the unit direction (ux, uy)."""
    hx, hy, _ = world.bodies[body].half_extents
    return abs(ux) * hx + abs(uy) * hy


def degenerate_routes(step: Step, world: World) -> list[str]:
    """Why each route body of a step is not on the way (an empty list: the route is sound)."""
    problems = []
    if not step.waypoints:
        return problems
    a, b = world.poses[step.source], world.poses[step.target]
    length = math.hypot(b.x - a.x, b.y - a.y)
    ux, uy = ((b.x - a.x) / length, (b.y - a.y) / length) if length > 1e-9 else (1.0, 0.0)
    for mode, body in step.waypoints:
        p = world.poses[body]
        along = (p.x - a.x) * ux + (p.y - a.y) * uy
        across = abs((p.x - a.x) * uy - (p.y - a.y) * ux)
        reach = _extent(world, body, ux, uy)
        words = f"'{'pass over' if mode == 'via' else 'avoid'} {body}'"
        if (along - reach < _extent(world, step.source, ux, uy)
                or length - along - reach < _extent(world, step.target, ux, uy)):
            problems.append(f"{words}: {body} is not between {step.source} and {step.target} "
                            f"(its footprint spans {100 * (along - reach):.1f} to "
                            f"{100 * (along + reach):.1f} cm along a {100 * length:.1f} cm path "
                            "and must clear both ends' footprints)")
        elif across > ROUTE_BAND:
            problems.append(f"{words}: {body} is {100 * across:.1f} cm off the straight path "
                            f"from {step.source} to {step.target} (at most {100 * ROUTE_BAND:g} "
                            "cm is on the way)")
    return problems
