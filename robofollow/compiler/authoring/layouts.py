"""Layouts -> poses: a layout is written as placements, or as operations on another layout
(`layout b from a { swap x y }`); every body is posed on the table, on another body or in a
bowl; a `recolor` gives a body another colour (recolours.py), kept by the layouts derived
from it. Checked here: cycles of derivation and of support, stacks at most MAX_STACK high, and
(footprints.py) footprints that stay on the table and clear of each other with the jitter at
its extremes. A problem of poses is reported at the statement that causes it, once: the
layouts derived from the first that has it, and keep it, are named there. Iterative throughout: neither a long chain of derived layouts nor a stack recurses."""

from __future__ import annotations

from dataclasses import dataclass, field

from lark import Token

from robofollow.compiler.authoring.footprints import Footprints, Spot
from robofollow.compiler.authoring.recolours import recolour
from robofollow.compiler.authoring.spec_checks import Checks
from robofollow.compiler.authoring.spec_syntax import Coordinates, LayoutNode, LayoutOp
from robofollow.compiler.scene.spec import (
    BOWL_FLOOR,
    MAX_STACK,
    Body,
    Colour,
    Layout,
    Placed,
)


@dataclass
class _Problem:
    """A problem of poses: reported once, at the first layout that has it, naming the others."""

    code: str
    message: str
    where: Token
    layouts: list[str] = field(default_factory=list)


class LayoutResolver:
    """A scene's layouts -> absolute poses and colours; problems go to `checks`. Bodies in
    `footprints.broken` (a bad attribute, reported there) are left out of the footprint and
    look-alike checks."""

    def __init__(self, checks: Checks, bodies: dict[str, Body],
                 points: dict[str, tuple[float, float]], bad_points: set[str], table: float,
                 footprints: Footprints):
        self.checks = checks
        self.bodies = bodies
        self.points = points
        self.bad_points = bad_points
        self.table = table
        self.footprints = footprints
        self.raw: dict[str, LayoutNode] = {}
        self.done: dict[str, dict[str, Spot] | None] = {}
        self.colours: dict[str, dict[str, Colour]] = {}  # by layout: its `recolor`s, inherited
        self.problems: dict[tuple, _Problem] = {}  # of poses, by key, in the order found
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
                placed = self.poses(self.done[layout], layout, quiet=base in self.unposed)
                if placed is None:
                    self.unposed.add(layout)
                else:
                    posed[layout] = Layout(name=layout, base=base, placed=placed,
                                           colours=self.colours[layout])
        self.report_problems()
        return {name: posed[name] for name in self.raw if name in posed}

    def base(self, name: str) -> str | None:
        base = self.raw[name].base
        return None if base is None else str(base)

    def known(self, token: Token) -> bool:
        if token not in self.bodies:
            self.checks.unknown_name("unknown-object", "object", token, self.bodies)
            return False
        return True

    def position(self, node: Coordinates | Token, body: str) -> tuple[float, float] | None:
        if isinstance(node, Token):
            if node in self.bad_points:  # already reported where the point is defined
                return None
            if node not in self.points:
                self.checks.unknown_name("unknown-point", "point", node,
                                         [*self.points, *sorted(self.bad_points)])
                return None
            return self.points[str(node)]
        return self.checks.coordinates(node, body)

    def arrangement(self, name: str) -> dict[str, Spot] | None:
        """body -> its spot, or None if the layout failed. The chain
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
                self.checks.unknown_name("undefined-layout", "layout", base, self.raw)
                return self.fail(chain)
            current = str(base)
        for layout in reversed(chain):
            base = self.base(layout)
            arrangement: dict[str, Spot] = {}
            colours: dict[str, Colour] = {}
            if base is not None:
                inherited = self.done[base]
                if inherited is None:  # its own names are checked still: every error at once
                    for op in self.raw[layout].ops:
                        self.names_known(op)
                    self.done[layout], self.colours[layout] = None, {}
                    continue
                arrangement, colours = dict(inherited), dict(self.colours[base])
            # every op, every error
            applied = [self.apply(op, arrangement, colours) for op in self.raw[layout].ops]
            self.done[layout] = arrangement if all(applied) else None
            self.colours[layout] = colours
        return self.done[name]

    def fail(self, chain: list[str]) -> None:
        for layout in chain:
            self.done.setdefault(layout, None)

    def apply(self, op: LayoutOp, arrangement: dict[str, Spot],
              colours: dict[str, Colour]) -> bool:
        """Apply one operation to the arrangement (a recolour: to `colours`); False
        (reported, or already reported) when it fails."""
        kind, other = op.kind, op.other
        if not self.names_known(op):
            return False
        first = str(op.body)
        if kind in ("swap", "move", "remove", "put_on", "put_in", "recolor") \
                and first not in arrangement:
            self.checks.error("not-in-layout", f"{first} is not in this layout", op.body)
            return False
        if kind == "recolor":
            return recolour(self.checks, op, self.bodies, self.footprints.broken, colours)
        if kind in ("at", "move"):
            position = self.position(op.position, first)
            if position is None:
                return False
            arrangement[first] = Spot("at", position, op.body, op.body)
        elif kind in ("on", "put_on"):
            arrangement[first] = Spot("on", str(other), op.body, op.body)
        elif kind in ("in_", "put_in"):
            if self.bodies[str(other)].kind != "bowl":
                self.checks.error("not-a-container", f"{other!s} is not a bowl", other)
                return False
            arrangement[first] = Spot("in", str(other), op.body, op.body)
        elif kind == "swap":
            second = str(other)
            if first == second:
                self.checks.error("swap-self", f"swap names {first} twice", other)
                return False
            if second not in arrangement:
                self.checks.error("not-in-layout", f"{second} is not in this layout", other)
                return False
            mine, theirs = arrangement[first], arrangement[second]
            arrangement[first] = Spot(theirs.how, theirs.value, theirs.written, op.body)
            arrangement[second] = Spot(mine.how, mine.value, mine.written, other)
        elif kind == "remove":
            resting = [b for b, spot in arrangement.items()
                       if spot.how != "at" and spot.value == first]
            if resting:
                self.checks.error("support-removed", f"{', '.join(resting)} rests on {first}",
                                  op.body)
                return False
            del arrangement[first]
        return True

    def names_known(self, op: LayoutOp) -> bool:
        """Whether the bodies (and the point) an operation names exist; each that does not is
        reported, with did-you-mean."""
        known = self.known(op.body) and (op.other is None or self.known(op.other))
        if known and op.kind in ("at", "move") and isinstance(op.position, Token):
            return self.position(op.position, str(op.body)) is not None
        return known

    def poses(self, arrangement: dict[str, Spot], layout: str,
              quiet: bool = False) -> dict[str, Placed] | None:
        """Every body's pose: a stack is walked down to the body on the table, then placed
        upwards (a loop; at most MAX_STACK bodies high). Quiet: only problems already found in
        another layout are recorded."""
        placed: dict[str, Placed] = {}
        height: dict[str, int] = {}  # bodies from this one down to the table, itself included

        def record(key: tuple, code: str, message: str, where: Token) -> None:
            self.record(key, code, message, where, layout, new=not quiet)

        for start in arrangement:
            stack = [start]
            while stack[-1] not in placed:
                body = stack[-1]
                spot = arrangement[body]
                if spot.how == "at":
                    break
                value = spot.value
                if value in stack:  # reported at the statement that closes the cycle
                    cycle = stack[stack.index(value):]
                    last = max((arrangement[b].by for b in cycle),
                               key=lambda token: (token.line, token.column))
                    record(("support-cycle", *sorted(cycle)), "support-cycle",
                           f"{body} rests on itself" if value == body else
                           f"{', '.join(cycle[:-1])} and {cycle[-1]} rest on each other "
                           f"({' on '.join([*cycle, value])})", last)
                    return None
                if value not in arrangement:
                    record(("not-in-layout", body, value), "not-in-layout",
                           f"{body} rests on {value}, which is not in this layout", spot.by)
                    return None
                stack.append(value)
            for body in reversed(stack):
                if body in placed:
                    continue
                spot = arrangement[body]
                how, value = spot.how, spot.value
                half = self.bodies[body].half_extents[2]
                if how == "at":
                    placed[body], height[body] = Placed(x=value[0], y=value[1],
                                                        z=self.table + half), 1
                    continue
                height[body] = height[value] + 1
                if height[body] > MAX_STACK:
                    record(("stack-too-tall", body), "stack-too-tall", f"{body} rests on a "
                           f"stack of {height[value]} bodies in layout {layout}; at most "
                           f"{MAX_STACK} bodies may rest on one another", spot.by)
                    return None
                support = placed[value]
                bottom = support.z - self.bodies[value].half_extents[2]
                z = (support.z + self.bodies[value].half_extents[2] + half if how == "on"
                     else bottom + BOWL_FLOOR + half)
                placed[body] = Placed(x=support.x, y=support.y, z=z, support=value, relation=how)
        self.footprints.check(placed, arrangement, layout, record)
        return placed  # supports before what rests on them

    def record(self, key: tuple, code: str, message: str, where: Token, layout: str,
               new: bool = True) -> None:
        """A problem of poses in a layout: the first layout that has it is where it is
        reported; a layout that keeps it (one derived from that one) is named there."""
        problem = self.problems.get(key)
        if problem is None and new:
            self.problems[key] = _Problem(code, message, where, [layout])
        elif problem is not None and layout not in problem.layouts:
            problem.layouts.append(layout)

    @property
    def troubled(self) -> set[str]:
        """The layouts with a problem of poses."""
        return {layout for problem in self.problems.values() for layout in problem.layouts}

    def report_problems(self) -> None:
        for problem in self.problems.values():
            first, *others = problem.layouts
            kept = ""
            if others:
                derived = all(self.derives(other, first) for other in others)
                kept = (f"; {'inherited by' if derived else 'the same in'} "
                        f"layout{'s' if len(others) > 1 else ''} {', '.join(others)}")
            self.checks.error(problem.code, problem.message + kept, problem.where)

    def derives(self, layout: str, ancestor: str) -> bool:
        """Whether `layout` is derived (at any depth) from `ancestor`."""
        seen: set[str] = set()
        while layout is not None and layout not in seen:
            seen.add(layout)
            layout = self.base(layout)
            if layout == ancestor:
                return True
        return False
