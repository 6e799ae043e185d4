"""Footprints of posed bodies: on the table top and clear of each other with the jitter at its
extremes (nothing rests on a ball). Each problem is measured in cm and placed at the statement
that causes it: the layout operation that puts the body there, or, when only the jitter
carries a body off the table, that body's `jitter` line."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from lark import Token

from robofollow.compiler.scene.spec import Body, Jitter, Placed
from robofollow.compiler.scene.workspace import table_bounds

ROUND_KINDS = ("sphere", "cylinder", "bowl")


@dataclass(frozen=True, slots=True)
class Spot:
    """Where a layout puts a body: `how` is at (value: (x, y)), on or in (value: a body).
    `written` is the statement that wrote the value, `by` the one that put this body there
    (a swap hands a body another's spot)."""

    how: str
    value: tuple[float, float] | str
    written: Token
    by: Token


# a problem found: its key (the same key in another layout is the same problem), code,
# message, and the token it is reported at
Record = Callable[[tuple, str, str, Token], None]


def overlap_depth(a: Body, pa: Placed, b: Body, pb: Placed, ja: Jitter, jb: Jitter) -> float:
    """How far two footprints can reach into each other for some offsets within their jitter
    ranges (m; 0 or less: they stay clear)."""
    dx = (pa.x - pb.x + ja.x[0] - jb.x[1], pa.x - pb.x + ja.x[1] - jb.x[0])
    dy = (pa.y - pb.y + ja.y[0] - jb.y[1], pa.y - pb.y + ja.y[1] - jb.y[0])
    gap_x = 0.0 if dx[0] <= 0 <= dx[1] else min(abs(dx[0]), abs(dx[1]))
    gap_y = 0.0 if dy[0] <= 0 <= dy[1] else min(abs(dy[0]), abs(dy[1]))
    if a.kind in ROUND_KINDS and b.kind in ROUND_KINDS:
        return a.half_extents[0] + b.half_extents[0] - math.hypot(gap_x, gap_y)
    return min(a.half_extents[0] + b.half_extents[0] - gap_x,
               a.half_extents[1] + b.half_extents[1] - gap_y)


def past_edge(body: Body, at: Placed, jitter: Jitter) -> float:
    """How far the footprint can reach past the table top's edge (m; 0 or less: it stays on)."""
    low_x, high_x, low_y, high_y = table_bounds()
    (hx, hy), (jx, jy) = body.half_extents[:2], (jitter.x, jitter.y)
    return max(low_x - (at.x + jx[0] - hx), at.x + jx[1] + hx - high_x,
               low_y - (at.y + jy[0] - hy), at.y + jy[1] + hy - high_y)


def cm(metres: float) -> str:
    """A length for people: '3.2 cm' ('0.04 cm' below a millimetre)."""
    return f"{100 * metres:.{1 if metres >= 0.001 else 2}f} cm"


def _at(token: Token) -> tuple[int, int]:
    return token.line, token.column


class Footprints:
    """The footprint checks of a scene's layouts; bodies in `broken` (a bad attribute,
    reported there) are left out. `jitter_at` holds the `jitter` statements by target."""

    def __init__(self, bodies: dict[str, Body], jitter: dict[str, Jitter],
                 jitter_at: dict[str, Token], broken: set[str]):
        self.bodies = bodies
        self.jitter = jitter
        self.jitter_at = jitter_at
        self.broken = broken

    def check(self, placed: dict[str, Placed], spots: dict[str, Spot], layout: str,
              record: Record) -> None:
        on_table = sorted(b for b, p in placed.items()
                          if p.relation == "table" and b not in self.broken)
        ranges = {b: self.jitter.get(b) or self.jitter.get("*") or Jitter() for b in on_table}
        for body in on_table:
            self.edge(body, placed[body], spots[body], ranges[body], layout, record)
        solid = [b for b in on_table if self.bodies[b].kind != "label"]
        for i, a in enumerate(solid):
            for b in solid[i + 1:]:
                self.overlap(a, b, placed, spots, ranges, layout, record)
        for body, at in placed.items():
            if at.relation == "on" and self.bodies[at.support].kind == "sphere" and not (
                    {body, at.support} & self.broken):
                record(("unstable-stack", _at(spots[body].by)), "unstable-stack",
                       f"{body} cannot rest on {at.support}, a sphere, in layout {layout}",
                       spots[body].by)

    def _shape(self, body: str) -> tuple:
        return self.bodies[body].kind, self.bodies[body].half_extents

    def _jitter_token(self, body: str) -> Token | None:
        """The `jitter` statement that applies to a body (None: none does)."""
        return self.jitter_at.get(body, self.jitter_at.get("*"))

    def edge(self, body: str, at: Placed, spot: Spot, jitter: Jitter, layout: str,
             record: Record) -> None:
        """The body's footprint past the table's edge: at its placement when it is there
        already, else at its jitter."""
        shape, low_x, high_x, low_y, high_y = self._shape(body), *table_bounds()
        table = f"(the table top: x in [{low_x:g}, {high_x:g}], y in [{low_y:g}, {high_y:g}])"
        beyond = past_edge(self.bodies[body], at, Jitter())
        if beyond > 0:
            record(("off-table", shape, at.x, at.y, _at(spot.written)), "off-table",
                   f"{body} at ({at.x:g}, {at.y:g}) reaches {cm(beyond)} past the table's "
                   f"edge in layout {layout} {table}", spot.by)
            return
        beyond = past_edge(self.bodies[body], at, jitter)
        if beyond > 0:
            where = self._jitter_token(body)
            record(("off-table", shape, at.x, at.y, _at(spot.written), _at(where)),
                   "off-table", f"the jitter of {body} can carry it {cm(beyond)} past the "
                   f"table's edge from ({at.x:g}, {at.y:g}) in layout {layout} {table}", where)

    def overlap(self, a: str, b: str, placed: dict[str, Placed], spots: dict[str, Spot],
                ranges: dict[str, Jitter], layout: str, record: Record) -> None:
        """Two footprints that overlap (or can, with the jitter), reported at the later of the
        statements that put the bodies there."""
        if _at(spots[a].by) > _at(spots[b].by):
            a, b = b, a  # b: placed later
        pair = self.bodies[a], placed[a], self.bodies[b], placed[b]
        nominal = overlap_depth(*pair, Jitter(), Jitter())
        depth = nominal if nominal > 0 else overlap_depth(*pair, ranges[a], ranges[b])
        if depth <= 0:
            return
        key = ("overlap", *sorted(((self._shape(x), placed[x].x, placed[x].y,
                                    _at(spots[x].written),
                                    nominal > 0 or (ranges[x].x, ranges[x].y))
                                   for x in (a, b)), key=repr))
        other = (f" ({a} is placed on line {spots[a].by.line})"
                 if spots[a].by.line != spots[b].by.line else "")
        if nominal > 0:
            message = f"{b} overlaps {a} by {cm(depth)} in layout {layout}{other}"
        else:
            lines = sorted({token.line for token in map(self._jitter_token, (a, b)) if token})
            message = (f"{b} and {a} can overlap by {cm(depth)} in layout {layout} with the "
                       f"jitter at its extremes{other} (jitter: line "
                       f"{', '.join(map(str, lines))})")
        record(key, "overlap", message, spots[b].by)
