"""Route geometry: which bodies a carry passes over, and whether a route constraint means
anything on a layout.

A route is judged at the nominal positions, in the table plane: the expert carries the object
high enough to clear every body (plans.py: LIFT above its grasp, or ROUTE_CLEARANCE above the
highest body on its route), so whether it passes over a body is a matter of footprints alone.
The straight path runs from the source's centre to the destination (the target's centre).
Carried along it, the object (at its pick-up yaw until it is turned for the set-down) sweeps a
band whose half-width is its footprint's half extent across the path.

- The ends' footprints: at pick-up the source's; at set-down the target's and, on or in the
  target, the carried object's centred there at its final yaw.
- On the way: a body's footprint clear of both ends' footprints along the path (between them),
  and its centre at most ROUTE_BAND to either side of the path.
- "pass over W": W's footprint overlaps neither end's footprint (else the carry passes over W
  trivially while picking up or setting down), and W is on the way (else the words ask for a
  detour backwards or far off the way).
- "avoid X": X lies on the straight path: between the ends, and its footprint within reach of
  the swept band (its centre at most the band's half-width plus its own half extent across the
  path, so that a straight carry would pass over part of it; further off, avoiding X costs
  nothing). And the detour exists: the expert carries over X's column mate instead
  (`passes_over`), so X's column must hold another movable body, and that body must be on the
  way as a "pass over" body is.
"""

from __future__ import annotations

import math

from robofollow.compiler.scene.behaviour import Step
from robofollow.compiler.scene.world import COLUMN_TOLERANCE, World

ROUTE_BAND = 0.08  # m: a route body lies at most this far to either side of the straight path
SET_DOWN_ON = ("on", "in")  # relations that set the carried object down centred on the target


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


def _footprint(world: World, body: str, yaw_degrees: float = 0.0) -> tuple[float, float]:
    """Half extents in x and y of a body's footprint turned by `yaw_degrees` (its bounding box
    in the table plane)."""
    hx, hy, _ = world.bodies[body].half_extents
    c, s = abs(math.cos(math.radians(yaw_degrees))), abs(math.sin(math.radians(yaw_degrees)))
    return c * hx + s * hy, s * hx + c * hy


class _Path:
    """The straight carry of a step: its ends, direction, and each end's footprints."""

    def __init__(self, step: Step, world: World):
        self.step, self.world = step, world
        a, b = world.poses[step.source], world.poses[step.target]
        self.a, self.b = a, b
        self.length = math.hypot(b.x - a.x, b.y - a.y)
        self.ux, self.uy = (((b.x - a.x) / self.length, (b.y - a.y) / self.length)
                            if self.length > 1e-9 else (1.0, 0.0))
        # (what, centre, half extents in x and y) of each footprint an end covers
        yaw = step.yaw_degrees or 0.0
        self.start = [(step.source, (a.x, a.y), _footprint(world, step.source))]
        self.end = [(step.target, (b.x, b.y), _footprint(world, step.target))]
        if step.relation in SET_DOWN_ON:
            self.end.append((f"{step.source} set down on {step.target}", (b.x, b.y),
                             _footprint(world, step.source, yaw)))

    def along(self, body: str) -> float:
        p = self.world.poses[body]
        return (p.x - self.a.x) * self.ux + (p.y - self.a.y) * self.uy

    def across(self, body: str) -> float:
        p = self.world.poses[body]
        return abs((p.x - self.a.x) * self.uy - (p.y - self.a.y) * self.ux)

    def end_reach(self, footprints) -> float:
        """How far an end's footprints reach along the path from its centre."""
        return max(abs(self.ux) * hx + abs(self.uy) * hy for _, _, (hx, hy) in footprints)

    def swept(self) -> float:
        """Half-width of the band the carried object sweeps (at its pick-up yaw)."""
        return _extent(self.world, self.step.source, self.uy, self.ux)


def _in_an_end(path: _Path, words: str, body: str) -> str | None:
    """Why `body` lies in the pick-up or set-down footprint, or None."""
    p = path.world.poses[body]
    hx, hy = _footprint(path.world, body)
    for moment, footprints in (("picking up", path.start), ("setting down", path.end)):
        for what, (cx, cy), (ex, ey) in footprints:
            dx, dy = abs(p.x - cx), abs(p.y - cy)
            if dx < hx + ex and dy < hy + ey:
                return (f"{words}: {body} lies in the footprint of {what} (centres "
                        f"{100 * dx:.1f} cm apart in x and {100 * dy:.1f} cm in y; clearing it "
                        f"takes {100 * (hx + ex):.1f} cm in x or {100 * (hy + ey):.1f} cm in y), "
                        f"so the carry passes over it while {moment}")
    return None


def _off_the_way(path: _Path, words: str, body: str) -> str | None:
    """Why `body` is not on the way of the straight carry, or None."""
    step = path.step
    along, across = path.along(body), path.across(body)
    reach = _extent(path.world, body, path.ux, path.uy)
    if (along - reach < path.end_reach(path.start)
            or path.length - along - reach < path.end_reach(path.end)):
        return (f"{words}: {body} is not between {step.source} and {step.target} "
                f"(its footprint spans {100 * (along - reach):.1f} to "
                f"{100 * (along + reach):.1f} cm along a {100 * path.length:.1f} cm path "
                "and must clear both ends' footprints)")
    if across > ROUTE_BAND:
        return (f"{words}: {body} is {100 * across:.1f} cm off the straight path "
                f"from {step.source} to {step.target} (at most {100 * ROUTE_BAND:g} "
                "cm is on the way)")
    return None


def _avoid_problem(path: _Path, words: str, body: str) -> str | None:
    """Why 'avoid `body`' asks for nothing: it is off the straight carry, or the detour over
    its column mate is missing or off the way; None when it is sound."""
    step, world = path.step, path.world
    swept, across = path.swept(), path.across(body)
    near = _extent(world, body, path.uy, path.ux)  # its half extent across the path
    if across > swept + near:
        return (f"{words}: {body} is {100 * across:.1f} cm off the straight path from "
                f"{step.source} to {step.target}; carried straight, {step.source} sweeps "
                f"{100 * swept:.1f} cm to either side and {body} reaches {100 * near:.1f} cm "
                f"towards the path, so a straight carry clears it by "
                f"{100 * (across - swept - near):.1f} cm (avoiding it must change the carry: "
                f"at most {100 * (swept + near):.1f} cm off)")
    mates = passes_over(step.model_copy(update={"waypoints": (("avoid", body),)}), world)
    if not mates:
        return (f"{words}: no other movable body stands in {body}'s column (within "
                f"{100 * COLUMN_TOLERANCE:g} cm of its x) to carry {step.source} over instead")
    for mate in mates:
        problem = (_in_an_end(path, f"{words} (over {mate} instead)", mate)
                   or _off_the_way(path, f"{words} (over {mate} instead)", mate))
        if problem:
            return problem
    return None


def degenerate_routes(step: Step, world: World) -> list[str]:
    """Why each route body of a step is not on the way (an empty list: the route is sound)."""
    problems: list[str] = []
    if not step.waypoints:
        return problems
    path = _Path(step, world)
    for mode, body in step.waypoints:
        words = f"'{'pass over' if mode == 'via' else 'avoid'} {body}'"
        problem = _in_an_end(path, words, body) or _off_the_way(path, words, body)
        if problem is None and mode == "avoid":
            problem = _avoid_problem(path, words, body)
        if problem:
            problems.append(problem)
    return problems
