"""A layout as geometry: where each body is, and which relations hold between bodies.

Relations come from positions and sizes with the named tolerances below, never from names.
Pure Python: the simulator and the oracle share these definitions without importing MuJoCo.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

from robofollow.compiler.scene.spec import Body, Scene

RELATION_CONE_DEG = 45.0  # deg: a direction relation holds within this angle of its axis
DIRECTION_MARGIN_DEG = 10.0  # deg: this near the cone's edge a viewer could read it either way
RELATION_RANGE = 0.20  # m: how far "next to X" reaches, and "to the left of X" as a destination
ON_XY_TOLERANCE = 0.02  # m: centre offset that still counts as "on top of"
CONTACT_TOLERANCE = 0.005  # m: gap that still counts as resting on / touching
EXTREME_MARGIN = 0.02  # m: the leftmost (...) object leads the runner-up by at least this
SIZE_MARGIN = 0.10  # a larger object's volume exceeds the runner-up's by this fraction
COLUMN_TOLERANCE = 0.03  # m: bodies this close in x stand in one column (a detour's choice)
ABOVE_XY_TOLERANCE = ON_XY_TOLERANCE  # m: centre offset that still counts as above / below
BETWEEN_BAND = 0.05  # m: how far off the line joining two landmarks "between" them reaches
NEAREST_MARGIN = 0.02  # m: the closest (farthest) object leads the runner-up by at least this
ORDINAL_MARGIN = EXTREME_MARGIN  # m: "the second from the left" stands clear of its neighbours

# direction of each horizontal relation in the world frame (+x right, +y away from the robot)
DIRECTIONS = {"left_of": (-1.0, 0.0), "right_of": (1.0, 0.0), "behind": (0.0, 1.0),
              "in_front_of": (0.0, -1.0)}
EXTREME_AXES = {"leftmost": (0, -1.0), "rightmost": (0, 1.0), "frontmost": (1, -1.0),
                "backmost": (1, 1.0)}
# the axis and sign an ordinal counts along, from its side ("from the left": increasing x)
ORDINAL_AXES = {"left": (0, 1.0), "right": (0, -1.0), "front": (1, 1.0), "back": (1, -1.0)}


@dataclass(frozen=True, slots=True)
class Pose:
    x: float
    y: float
    z: float


class World:
    """The bodies of one layout, at nominal positions plus optional jitter offsets."""

    def __init__(self, scene: Scene, layout: str,
                 offsets: dict[str, tuple[float, float]] | None = None,
                 positions: dict[str, tuple[float, float, float]] | None = None):
        """Bodies at nominal positions plus `offsets`, or exactly at `positions` (e.g. as
        measured in a simulation) where given."""
        self.scene = scene
        self.layout = scene.layouts[layout]
        self.table = scene.table_height
        self.bodies: dict[str, Body] = scene.bodies_in(layout)
        offsets = offsets or {}
        self.poses: dict[str, Pose] = {b: Pose(*map(float, p)) for b, p in (positions or {}).items()}
        self.shifted: set[str] = set(self.poses)  # bodies away from their nominal positions
        for body in self.layout.placed:
            self._pose(body, offsets)

    def _pose(self, body: str, offsets) -> Pose:
        """The body's pose; a stacked or contained body follows its support (walked down the
        stack in a loop, however tall it is)."""
        stack = [body]
        while stack[-1] not in self.poses and self.layout.placed[stack[-1]].support is not None:
            stack.append(self.layout.placed[stack[-1]].support)
        for name in reversed(stack):
            if name in self.poses:
                continue
            placed = self.layout.placed[name]
            if placed.support is None:
                dx, dy = offsets.get(name, (0.0, 0.0))
                self.poses[name] = Pose(placed.x + dx, placed.y + dy, placed.z)
                shifted = (dx, dy) != (0.0, 0.0)
            else:
                support = self.poses[placed.support]
                self.poses[name] = Pose(support.x, support.y, placed.z)
                shifted = placed.support in self.shifted
            if shifted:
                self.shifted.add(name)
        return self.poses[body]

    @property
    def movable(self) -> list[str]:
        return [b for b, body in self.bodies.items() if not body.fixture]

    def column_mates(self, body: str, excluding: tuple[str, ...] = ()) -> list[str]:
        """Movable bodies standing in `body`'s column (within COLUMN_TOLERANCE in x)."""
        x = self.poses[body].x
        return [b for b in self.movable if b != body and b not in excluding
                and abs(self.poses[b].x - x) <= COLUMN_TOLERANCE]

    def carried_by(self, body: str) -> list[str]:
        """Bodies the layout puts on (or in) `body`."""
        return [b for b, placed in self.layout.placed.items() if placed.support == body]

    def bottom(self, body: str) -> float:
        return self.poses[body].z - self.bodies[body].half_extents[2]

    def top(self, body: str) -> float:
        return self.poses[body].z + self.bodies[body].half_extents[2]

    def related(self, a: str, relation: str, b: str) -> bool:
        """Whether `a <relation> b` holds ('table' may stand as b for 'touching')."""
        if relation == "touching":
            if b == "table":
                return abs(self.bottom(a) - self.table) <= CONTACT_TOLERANCE
            return self._touching(a, b)
        pa, pb = self.poses[a], self.poses[b]
        if relation in ("above", "below"):
            upper, lower = (a, b) if relation == "above" else (b, a)
            return (math.hypot(pa.x - pb.x, pa.y - pb.y) <= ABOVE_XY_TOLERANCE
                    and self.bottom(upper) >= self.top(lower) - CONTACT_TOLERANCE)
        if relation == "on":
            return (math.hypot(pa.x - pb.x, pa.y - pb.y) <= ON_XY_TOLERANCE
                    and abs(self.bottom(a) - self.top(b)) <= CONTACT_TOLERANCE)
        if relation == "in":
            bowl = self.bodies[b]
            return (bowl.kind == "bowl"
                    and math.hypot(pa.x - pb.x, pa.y - pb.y) <= bowl.half_extents[0]
                    and self.bottom(a) < self.top(b))
        if relation == "next_to":
            return (not self._stacked(a, b)
                    and 0 < math.hypot(pa.x - pb.x, pa.y - pb.y) <= RELATION_RANGE)
        angle = self.off_axis(a, relation, b)
        return angle is not None and angle <= RELATION_CONE_DEG

    def off_axis(self, a: str, relation: str, b: str) -> float | None:
        """How far (deg) `a` stands off the direction `relation` names from `b`, as a viewer
        sees it: at any distance, and None where one rests on or in the other (a support is
        no neighbour) or they stand at one spot."""
        if self._stacked(a, b):
            return None
        pa, pb = self.poses[a], self.poses[b]
        dx, dy = pa.x - pb.x, pa.y - pb.y
        length = math.hypot(dx, dy)
        if length < 1e-9:
            return None
        direction = DIRECTIONS[relation]
        cosine = (dx * direction[0] + dy * direction[1]) / length
        return math.degrees(math.acos(max(-1.0, min(1.0, cosine))))

    def _stacked(self, a: str, b: str) -> bool:
        """Whether one body rests on or in the other (as measured, settled bodies included)."""
        return any(self.related(upper, relation, lower) for upper, lower in ((a, b), (b, a))
                   for relation in ("on", "in"))

    def between(self, body: str, a: str, b: str) -> bool:
        """Whether `body` stands between `a` and `b`: its centre projects strictly inside the
        segment joining theirs, within BETWEEN_BAND of it."""
        p, pa, pb = self.poses[body], self.poses[a], self.poses[b]
        dx, dy = pb.x - pa.x, pb.y - pa.y
        length = math.hypot(dx, dy)
        if length < 1e-9:
            return False
        along = ((p.x - pa.x) * dx + (p.y - pa.y) * dy) / length
        across = abs((p.x - pa.x) * dy - (p.y - pa.y) * dx) / length
        return 0.0 < along < length and across <= BETWEEN_BAND

    def distance(self, a: str, b: str) -> float:
        """Distance between two bodies' centres in the table plane."""
        pa, pb = self.poses[a], self.poses[b]
        return math.hypot(pa.x - pb.x, pa.y - pb.y)

    def _touching(self, a: str, b: str) -> bool:
        pa, pb = self.poses[a], self.poses[b]
        ha, hb = self.bodies[a].half_extents, self.bodies[b].half_extents
        gaps = (abs(pa.x - pb.x) - ha[0] - hb[0], abs(pa.y - pb.y) - ha[1] - hb[1],
                abs(pa.z - pb.z) - ha[2] - hb[2])
        return max(gaps) <= CONTACT_TOLERANCE


def in_cone(dx: float, dy: float, direction: tuple[float, float]) -> bool:
    """Whether the offset (dx, dy) points within RELATION_CONE_DEG of `direction`."""
    length = math.hypot(dx, dy)
    if length < 1e-9:
        return False
    cosine = (dx * direction[0] + dy * direction[1]) / length
    return cosine >= math.cos(math.radians(RELATION_CONE_DEG)) - 1e-12


def sample_offsets(scene: Scene, layout: str, rng) -> dict[str, tuple[float, float]]:
    """Seeded start jitter: a uniform (dx, dy) per body that rests on the table, drawn from
    its jitter range in layout order (stacked and contained bodies follow their support)."""
    offsets = {}
    for body, placed in scene.layouts[layout].placed.items():
        if placed.support is None:
            jitter = scene.jitter_of(body)
            offsets[body] = (float(rng.uniform(*jitter.x)), float(rng.uniform(*jitter.y)))
    return offsets


def _corner(scene: Scene, body: str, index: tuple[int, int]) -> tuple[float, float]:
    jitter = scene.jitter_of(body)
    return jitter.x[index[0]], jitter.y[index[1]]


CORNERS = tuple(itertools.product((0, 1), (0, 1)))
_SIDES = (("low", "high"), ("low", "high"))


def corner_worlds(scene: Scene, layout: str) -> list[World]:
    """The layout at nominal positions, then with every body at the same corner of its jitter
    range (four cases)."""
    return [world for _, world in jitter_cases(scene, layout, alone=False)]


def jitter_worlds(scene: Scene, layout: str) -> list[World]:
    """The corner worlds, then each body alone at each corner of its jitter range."""
    return [world for _, world in jitter_cases(scene, layout)]


def jitter_cases(scene: Scene, layout: str, alone: bool = True) -> list[tuple[str, World]]:
    """jitter_worlds (corner_worlds without the cases of one body `alone`), each with a
    description of its case: case i is jitter_worlds(...)[i]."""
    bodies = [b for b, p in scene.layouts[layout].placed.items() if p.support is None]
    cases = [("the nominal positions", World(scene, layout))]
    for c in CORNERS:
        cases.append((f"every body at its {_SIDES[0][c[0]]}-x, {_SIDES[1][c[1]]}-y jitter corner",
                      World(scene, layout, {b: _corner(scene, b, c) for b in bodies})))
    for b in bodies if alone else ():
        for c in CORNERS:
            dx, dy = _corner(scene, b, c)
            if (dx, dy) != (0.0, 0.0):
                cases.append((f"{b} alone moved ({100 * dx:+.1f}, {100 * dy:+.1f}) cm",
                              World(scene, layout, {b: (dx, dy)})))
    return cases
