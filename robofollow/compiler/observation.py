"""Layouts as a policy sees them: bodies by appearance and position, never by name.

Two layouts are the same observation when a permutation of identical-looking bodies (same
kind, size and colour) maps one onto the other, every body within OBSERVATION_TOLERANCE of
its image and resting on (or in) a body that looks the same. Swapping two identical cubes
changes nothing a camera sees.
"""

from __future__ import annotations

import math

from robofollow.compiler.spec import Body, Scene
from robofollow.compiler.world import World

OBSERVATION_TOLERANCE = 0.005  # m: bodies this close look to be in the same place
APPEARANCE_TOLERANCE = 0.002  # m (sizes) and 0.02 (rgb): bodies this alike look the same


def appearance(body: Body) -> tuple:
    """What a camera sees of a body, rounded to the tolerances: kind, size, colour."""
    return (body.kind,
            tuple(round(h / APPEARANCE_TOLERANCE) for h in body.half_extents),
            tuple(round(c / 0.02) for c in body.rgb))


def _seen(scene: Scene, layout: str) -> list[tuple[tuple, tuple[float, float, float], tuple]]:
    """(appearance, position, what it rests on as (relation, appearance)) per body."""
    world, placed = World(scene, layout), scene.layouts[layout].placed
    seen = []
    for name, body in world.bodies.items():
        pose, where = world.poses[name], placed[name]
        under = None if where.support is None else appearance(scene.bodies[where.support])
        seen.append((appearance(body), (pose.x, pose.y, pose.z), (where.relation, under)))
    return seen


def same_observation(scene: Scene, a: str, b: str) -> bool:
    """Whether layouts `a` and `b` of a scene look the same (see the module docstring)."""
    first, second = _seen(scene, a), _seen(scene, b)
    if sorted(x[0] for x in first) != sorted(x[0] for x in second):
        return False
    return _match(first, second)


def _match(left: list, right: list) -> bool:
    """A bijection pairing each body with a look-alike at the same place (backtracking)."""
    if not left:
        return True
    look, position, rest = left[0]
    for index, (other_look, other_position, other_rest) in enumerate(right):
        if (other_look == look and other_rest == rest
                and math.dist(position, other_position) <= OBSERVATION_TOLERANCE
                and _match(left[1:], right[:index] + right[index + 1:])):
            return True
    return False


def look_alike(scene: Scene, layout: str, layouts) -> str | None:
    """The first of `layouts` that looks the same as `layout`, if any."""
    return next((other for other in layouts if same_observation(scene, layout, other)), None)
