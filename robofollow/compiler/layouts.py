"""Layouts -> poses: a layout is written as placements, or as operations on another layout
(`layout b from a { swap x y }`); every body is posed on the table, on another body or in a
bowl. Checked here: cycles of derivation and of support, stacks at most MAX_STACK high, and
footprints that stay on the table and clear of each other with the jitter at its extremes.
Iterative throughout: neither a long chain of derived layouts nor a stack recurses."""

from __future__ import annotations

import math

from lark import Token

from robofollow.compiler.spec import MAX_STACK, Body, Jitter, Layout, Placed
from robofollow.compiler.spec_checks import Checks
from robofollow.compiler.spec_syntax import Coordinates, LayoutNode, LayoutOp
from robofollow.compiler.workspace import table_bounds

BOWL_FLOOR = 0.005  # m: height of a bowl's inner floor above its bottom
BOWL_WALL = 0.004  # m: a bowl's wall thickness (its radius is the wall's outside)
BOWL_SEGMENTS = 16  # flat wall boxes around a bowl (face normals every 360/16 deg from +x)


class LayoutResolver:
    """A scene's layouts -> absolute poses; problems go to `checks`. Bodies in `broken` (a
    bad attribute, reported there) are left out of the footprint checks."""

    def __init__(self, checks: Checks, bodies: dict[str, Body],
                 points: dict[str, tuple[float, float]], bad_points: set[str], table: float,
                 jitter: dict[str, Jitter], broken: set[str]):
        self.checks = checks
        self.broken = broken
        self.jitter = jitter
        self.bodies = bodies
        self.points = points
        self.bad_points = bad_points
        self.table = table
        self.raw: dict[str, LayoutNode] = {}
        self.done: dict[str, dict[str, tuple] | None] = {}
        self.reported: set[tuple] = set()  # geometry problems already reported (once each)
        self.unposed: set[str] = set()  # layouts whose bodies could not be posed

    def resolve(self, nodes: list[LayoutNode]) -> dict[str, Layout]:
        for node in nodes:
            name = node.name
            if name in self.raw:
                self.checks.error("duplicate-layout", f"layout {name!s} is defined twice", name)
            self.raw[str(name)] = node
        for name in self.raw:
            self.arrangement(name)
        posed: dict[str, Layout] = {}
        for name in self.raw:
            chain = []  # the layout and its bases not yet posed, posed bases first
            current = name
            while current is not None and current not in posed and current not in self.unposed \
                    and self.done.get(current) is not None:
                chain.append(current)
                current = self.base(current)
            for layout in reversed(chain):
                base = self.base(layout)
                # derived from a layout that could not be posed: fails quietly if it also fails
                placed = self.poses(self.done[layout], self.raw[layout].name,
                                    quiet=base in self.unposed)
                if placed is None:
                    self.unposed.add(layout)
                else:
                    posed[layout] = Layout(name=layout, base=base, placed=placed)
        return {name: posed[name] for name in self.raw if name in posed}

    def base(self, name: str) -> str | None:
        base = self.raw[name].base
        return None if base is None else str(base)

    def known(self, token: Token) -> bool:
        if token not in self.bodies:
            self.checks.error("unknown-object", f"no object named {token!s}", token)
            return False
        return True

    def position(self, node: Coordinates | Token, body: str) -> tuple[float, float] | None:
        if isinstance(node, Token):
            if node in self.bad_points:  # already reported where the point is defined
                return None
            if node not in self.points:
                self.checks.error("unknown-point", f"no point named {node!s}", node)
                return None
            return self.points[str(node)]
        return self.checks.coordinates(node, body)

    def arrangement(self, name: str) -> dict[str, tuple] | None:
        """body -> ("at", (x, y)) | ("on", body) | ("in", body), or None if it failed. The chain
        of bases is followed down to a resolved layout (or a cycle, or an undefined base), then
        resolved back up in a loop."""
        chain: list[str] = []
        current = name
        while current not in self.done:
            if current in chain:
                cycle = chain[chain.index(current):] + [current]
                self.checks.error("layout-cycle", "layouts derive from each other: "
                                  + " -> ".join(cycle), self.raw[current].name)
                return self.fail(chain)
            chain.append(current)
            base = self.raw[current].base
            if base is None:
                break  # written as placements
            if base not in self.raw:
                self.checks.error("undefined-layout", f"no layout named {base!s}", base)
                return self.fail(chain)
            current = str(base)
        for layout in reversed(chain):
            base = self.base(layout)
            arrangement: dict[str, tuple] = {}
            if base is not None:
                inherited = self.done[base]
                if inherited is None:
                    return self.fail(chain)
                arrangement = dict(inherited)
            # every op, every error
            applied = [self.apply(op, arrangement) for op in self.raw[layout].ops]
            self.done[layout] = arrangement if all(applied) else None
        return self.done[name]

    def fail(self, chain: list[str]) -> None:
        for layout in chain:
            self.done.setdefault(layout, None)
        return None

    def apply(self, op: LayoutOp, arrangement: dict[str, tuple]) -> bool:
        """Apply one operation; False (reported, or already reported) when it fails."""
        kind, other = op.kind, op.other
        if not (self.known(op.body) and (other is None or self.known(other))):
            return False
        first = str(op.body)
        if kind in ("swap", "move", "remove", "put_on", "put_in") and first not in arrangement:
            self.checks.error("not-in-layout", f"{first} is not in this layout", op.body)
            return False
        if kind in ("at", "move"):
            position = self.position(op.position, first)
            if position is None:
                return False
            arrangement[first] = ("at", position)
        elif kind in ("on", "put_on"):
            arrangement[first] = ("on", str(other))
        elif kind in ("in_", "put_in"):
            if self.bodies[str(other)].kind != "bowl":
                self.checks.error("not-a-container", f"{other!s} is not a bowl", other)
                return False
            arrangement[first] = ("in", str(other))
        elif kind == "swap":
            second = str(other)
            if first == second:
                self.checks.error("swap-self", f"swap names {first} twice", other)
                return False
            if second not in arrangement:
                self.checks.error("not-in-layout", f"{second} is not in this layout", other)
                return False
            arrangement[first], arrangement[second] = arrangement[second], arrangement[first]
        elif kind == "remove":
            resting = [b for b, (how, where) in arrangement.items() if how != "at" and where == first]
            if resting:
                self.checks.error("support-removed", f"{', '.join(resting)} rests on {first}",
                                  op.body)
                return False
            del arrangement[first]
        return True

    def poses(self, arrangement: dict[str, tuple], where: Token,
              quiet: bool = False) -> dict[str, Placed] | None:
        """Every body's pose: a stack is walked down to the body on the table, then placed
        upwards (a loop; at most MAX_STACK bodies high)."""
        placed: dict[str, Placed] = {}
        report = (lambda *_: None) if quiet else self.report
        height: dict[str, int] = {}  # bodies from this one down to the table, itself included
        for start in arrangement:
            stack = [start]
            while stack[-1] not in placed:
                body = stack[-1]
                how, value = arrangement[body]
                if how == "at":
                    break
                if value in stack:
                    report(("support-cycle", body, value), "support-cycle",
                           f"{body} rests on itself" if value == body else
                           f"{body} and {value} rest on each other", where)
                    return None
                if value not in arrangement:
                    report(("not-in-layout", body, value), "not-in-layout",
                           f"{body} rests on {value}, which is not in this layout", where)
                    return None
                stack.append(value)
            for body in reversed(stack):
                if body in placed:
                    continue
                how, value = arrangement[body]
                half = self.bodies[body].half_extents[2]
                if how == "at":
                    placed[body], height[body] = Placed(x=value[0], y=value[1],
                                                        z=self.table + half), 1
                    continue
                height[body] = height[value] + 1
                if height[body] > MAX_STACK:
                    report(("stack-too-tall", body), "stack-too-tall", f"{body} rests on a "
                           f"stack of {height[value]} bodies in layout {where!s}; at most "
                           f"{MAX_STACK} bodies may rest on one another", where)
                    return None
                support = placed[value]
                bottom = support.z - self.bodies[value].half_extents[2]
                z = (support.z + self.bodies[value].half_extents[2] + half if how == "on"
                     else bottom + BOWL_FLOOR + half)
                placed[body] = Placed(x=support.x, y=support.y, z=z, support=value, relation=how)
        self.check_overlaps(placed, where)
        return placed  # supports before what rests on them

    def report(self, key: tuple, code: str, message: str, where: Token) -> None:
        """A problem of poses, reported at the first layout that has it (a derived layout
        that keeps it does not repeat it, and fails, or is checked, without a second report)."""
        if key not in self.reported:
            self.reported.add(key)
            self.checks.error(code, message, where)

    def check_overlaps(self, placed: dict[str, Placed], where: Token) -> None:
        """Bodies on the table stay on it and clear of each other with the jitter at its
        extremes; nothing is stacked on a body that rolls. A broken body (a bad attribute,
        reported there) is left out."""
        broken = self.broken
        on_table = sorted(b for b, p in placed.items() if p.relation == "table" and b not in broken)
        ranges = {b: self.jitter.get(b) or self.jitter.get("*") or Jitter() for b in on_table}
        low_x, high_x, low_y, high_y = table_bounds()
        for body in on_table:
            half, at, jitter = self.bodies[body].half_extents, placed[body], ranges[body]
            if (at.x + jitter.x[0] - half[0] < low_x or at.x + jitter.x[1] + half[0] > high_x
                    or at.y + jitter.y[0] - half[1] < low_y
                    or at.y + jitter.y[1] + half[1] > high_y):
                self.report(("off-table", body, at.x, at.y), "off-table",
                            f"{body} at ({at.x:g}, {at.y:g}) can leave the table (x in "
                            f"[{low_x:g}, {high_x:g}], y in [{low_y:g}, {high_y:g}]) in layout "
                            f"{where!s}", where)
        solid = [b for b in on_table if self.bodies[b].kind != "label"]
        for i, a in enumerate(solid):
            for b in solid[i + 1:]:
                pair = self.bodies[a], placed[a], self.bodies[b], placed[b]
                key = ("overlap", a, placed[a].x, placed[a].y, b, placed[b].x, placed[b].y)
                if _footprints_overlap(*pair, Jitter(), Jitter()):
                    self.report(key, "overlap", f"{a} and {b} overlap in layout {where!s}", where)
                elif _footprints_overlap(*pair, ranges[a], ranges[b]):
                    self.report(key, "overlap", f"{a} and {b} can overlap in layout {where!s} "
                                "with the jitter at its extremes", where)
        for body, at in placed.items():
            if at.relation == "on" and self.bodies[at.support].kind == "sphere" and not (
                    {body, at.support} & broken):
                self.report(("unstable-stack", body, at.support), "unstable-stack",
                            f"{body} cannot rest on {at.support}, a sphere, in layout "
                            f"{where!s}", where)


def _footprints_overlap(a: Body, pa: Placed, b: Body, pb: Placed, ja: Jitter,
                        jb: Jitter) -> bool:
    """Whether two footprints can overlap for some offsets within their jitter ranges."""
    dx = (pa.x - pb.x + ja.x[0] - jb.x[1], pa.x - pb.x + ja.x[1] - jb.x[0])
    dy = (pa.y - pb.y + ja.y[0] - jb.y[1], pa.y - pb.y + ja.y[1] - jb.y[0])
    gap_x = 0.0 if dx[0] <= 0 <= dx[1] else min(abs(dx[0]), abs(dx[1]))
    gap_y = 0.0 if dy[0] <= 0 <= dy[1] else min(abs(dy[0]), abs(dy[1]))
    round_kinds = ("sphere", "cylinder", "bowl")
    if a.kind in round_kinds and b.kind in round_kinds:
        return math.hypot(gap_x, gap_y) < a.half_extents[0] + b.half_extents[0]
    return (gap_x < a.half_extents[0] + b.half_extents[0]
            and gap_y < a.half_extents[1] + b.half_extents[1])
