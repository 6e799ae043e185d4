"""Layouts as a policy sees them: bodies by appearance and position, never by name.

Two layouts are the same observation when a permutation of identical-looking bodies (same
kind, size and colour; a perfect bipartite matching) maps one onto the other, every body within OBSERVATION_TOLERANCE of
its image and resting on (or in) a body that looks the same. Swapping two identical cubes
changes nothing a camera sees.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

from robofollow.compiler.scene.spec import Body, Scene
from robofollow.compiler.scene.world import World

OBSERVATION_TOLERANCE = 0.005  # m: bodies this close look to be in the same place
SIZE_TOLERANCE = 0.002  # m: half extents this close look the same
COLOUR_TOLERANCE = 0.02  # rgb components (0-1) this close look the same


def looks_alike(a: Body | None, b: Body | None) -> bool:
    """Whether two bodies (or two absences of one) look the same: kind, size and colour."""
    if a is None or b is None:
        return a is b
    return (a.kind == b.kind
            and all(abs(x - y) <= SIZE_TOLERANCE
                    for x, y in zip(a.half_extents, b.half_extents, strict=True))
            and all(abs(x - y) <= COLOUR_TOLERANCE for x, y in zip(a.rgb, b.rgb, strict=True)))


def misnamed_twin(body: Body, others: Iterable[Body]) -> Body | None:
    """The first of `others` that looks the same as `body` but has another colour word."""
    return next((other for other in others
                 if looks_alike(other, body) and other.color != body.color), None)


def _seen(scene: Scene, layout: str) -> list[tuple]:
    """(body, position, relation to what it rests on, that support's body) per body."""
    world, placed = World(scene, layout), scene.layouts[layout].placed
    return [(body, (world.poses[name].x, world.poses[name].y, world.poses[name].z),
             placed[name].relation,
             None if placed[name].support is None else world.bodies[placed[name].support])
            for name, body in world.bodies.items()]


def same_observation(scene: Scene, a: str, b: str) -> bool:
    """Whether layouts `a` and `b` of a scene look the same (see the module docstring)."""
    import networkx as nx  # (a tenth of a second to import: only when layouts are compared)

    first, second = _seen(scene, a), _seen(scene, b)
    if len(first) != len(second):
        return False
    graph = nx.Graph()
    graph.add_nodes_from(range(len(first)))
    graph.add_edges_from(
        (i, len(first) + j) for i, (body, position, relation, support) in enumerate(first)
        for j, (other, other_position, other_relation, other_support) in enumerate(second)
        if looks_alike(body, other) and relation == other_relation
        and looks_alike(support, other_support)
        and math.dist(position, other_position) <= OBSERVATION_TOLERANCE)
    matching = nx.bipartite.maximum_matching(graph, top_nodes=range(len(first)))
    return len(matching) == 2 * len(first)  # the matching maps both ways


def look_alike(scene: Scene, layout: str, layouts) -> str | None:
    """The first of `layouts` that looks the same as `layout`, if any."""
    return next((other for other in layouts if same_observation(scene, layout, other)), None)
