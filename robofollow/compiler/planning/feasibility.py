"""Whether the expert can perform a behaviour on a layout, decided from geometry alone (no
physics), before anything is simulated:

- every point of the expert's plan at the nominal positions lies within its arm's reach
  (workspace.py), with room to spare for the layout's largest jitter offset;
- every body to grip fits the open gripper;
- no arm is asked to act while it still holds what an earlier step picked up;
- nothing rests on a body to move;
- a stack goes onto a free, flat top; a relative placement finds a free spot beside its
  landmark;
- the gripper, lowered to grasp (or to push), clears every other body, at every jitter
  extreme (finger clearance);
- a placement into a bowl finds it empty: nobody sits in it at the start, and no earlier step
  puts something there;
- a stacked body comes to rest on its support: its centre stays over the support's top after
  the expert's placing error and the slide its release speed allows at the stack's friction.

Physical tolerances (measured with the expert in simulation, MuJoCo, the shipped robot):

- fingers: around a 4 x 4 x 4 cm cube a 4 cm neighbour along the closing axis at 6.5 cm
  (centre to centre) or more is untouched; at 6.2-6.4 cm it is nudged 0.1-0.25 cm; at 6.1 cm
  or less the grasp fails or the neighbour topples. The geometric limit is 6.35 cm (2 cm half
  cube + OPEN_FINGER_REACH): the real fingers land within ~1 mm of it (FINGER_MARGIN), and
  only an overlap past 2 mm makes the grasp fail. Across the closing axis, a neighbour 0.2 cm
  clear of the fingers' width is untouched, one overlapping it by 0.2 cm makes the grasp fail.
- stacks: the expert releases a top within 0.03 cm of its support's centre and it moves at most
  0.8 cm/s afterwards (0.3 cm/s on flat supports at least 1 cm wide); two equal cubes, equal
  cylinders, a 6 cm cube on a 4 cm cylinder stay stacked down to friction 0.001 (the lowest a
  spec may give); a 4 cm cube on a 2 or 4 mm wide pin falls at friction 0.001 and stays at 0.5.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from robofollow.compiler.planning.plans import place_spot, plan, push_points
from robofollow.compiler.scene import workspace
from robofollow.compiler.scene.behaviour import Behaviour, Step, describe_steps
from robofollow.compiler.scene.spec import BOWL_FLOOR, BOWL_SEGMENTS, BOWL_WALL
from robofollow.compiler.scene.world import ON_XY_TOLERANCE, World, jitter_cases

ROLLING = ("sphere",)  # kinds nothing can be stacked on
ROUND = ("sphere", "cylinder")  # kinds with a round footprint

# m: how far the open fingers reach from the grasp centre along their closing axis: each
# finger's inner face stands half the opening out, its outer face a finger's thickness further
OPEN_FINGER_REACH = workspace.GRIPPER_OPENING / 2 + workspace.FINGER_THICKNESS
# m: clearance kept between the gripper's swept footprint and any other body: the fingers land
# within ~1 mm of their nominal place (IK tolerance, tracking); measured, see above
FINGER_MARGIN = 0.001
_BOWL_FACES = [2 * math.pi * i / BOWL_SEGMENTS for i in range(BOWL_SEGMENTS)]  # face normals
GRAVITY = 9.81  # m/s^2
STACK_PLACE_ERROR = 0.0005  # m: the expert's release point off the support's centre (its IK
#   position tolerance; measured: 0.02-0.03 cm)
STACK_RELEASE_SPEED = 0.01  # m/s: the top's horizontal speed after release (measured: at most
#   0.8 cm/s), which friction mu turns into a slide of STACK_RELEASE_SPEED^2 / (2 mu g)


def infeasible(behaviour: Behaviour, world: World) -> list[str]:
    """Why the expert cannot perform `behaviour` on a layout at its nominal positions (empty:
    it can)."""
    return (_holding(behaviour) + _handling(behaviour, world) + _occupied(behaviour, world)
            + _reach(behaviour, world) + _clearance(behaviour, world))


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
            elif world.bodies[step.target].kind not in ROLLING:
                problems += _unstable(step, world)
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
        return [(f"{problems[0]} (and {len(problems) - 1} more plan point"
                 f"{'s' if len(problems) > 2 else ''})")]
    return problems


def friction(world: World, body: str) -> float:
    """The body's sliding friction as simulated (a fixture's is fixed)."""
    spec = world.bodies[body]
    return workspace.FIXTURE_FRICTION if spec.fixture else (spec.friction
                                                            or workspace.DEFAULT_FRICTION)


def stack_friction_bound(margin: float) -> float:
    """The least friction that keeps a released top's slide within `margin` (m) beyond the
    expert's placing error (inf: no friction does)."""
    room = margin - STACK_PLACE_ERROR
    return STACK_RELEASE_SPEED ** 2 / (2 * GRAVITY * room) if room > 0 else math.inf


def _unstable(step: Step, world: World) -> list[str]:
    """A stack whose top would not come to rest on its support: the top's centre must stay over
    the support's top face (its narrower half-width, a round top's radius) and within
    ON_XY_TOLERANCE of its centre. MuJoCo uses the larger friction of the two bodies."""
    support = world.bodies[step.target]
    half = support.half_extents
    margin = min(half[0] if support.kind in ROUND else min(half[:2]), ON_XY_TOLERANCE)
    mu = max(friction(world, step.source), friction(world, step.target))
    bound = stack_friction_bound(margin)
    if mu >= bound:
        return []
    if math.isinf(bound):
        return [(f"{step.source} would not rest on {step.target}: its top leaves "
                 f"{100 * margin:.2f} cm around the centre, within the expert's "
                 f"{100 * STACK_PLACE_ERROR:.2f} cm placing error")]
    slide = STACK_RELEASE_SPEED ** 2 / (2 * GRAVITY * mu)
    return [(f"{step.source} would slide off {step.target}: at friction {mu:g} it slides "
             f"{100 * slide:.1f} cm after release, and {step.target}'s top leaves "
             f"{100 * margin:.1f} cm (friction {bound:.2g} or more needed)")]


def _occupied(behaviour: Behaviour, world: World) -> list[str]:
    """Placements into a bowl that something already occupies: in it at the start, or put
    there by an earlier step (and not taken out since)."""
    inside: dict[str, list[str]] = {}
    for bowl, body in world.bodies.items():
        if body.kind == "bowl":
            inside[bowl] = [b for b in world.bodies if b != bowl and (
                world.layout.placed[b].support == bowl or world.related(b, "in", bowl))]
    problems = []
    for step in behaviour.steps:
        for occupants in inside.values():
            if step.source in occupants:
                occupants.remove(step.source)
        if step.action == "place" and step.relation == "in" and step.target in inside:
            occupants = inside[step.target]
            if occupants:
                problems.append(f"{step.target} is already occupied by {', '.join(occupants)}; "
                                f"{step.source} has no room in it")
            occupants.append(step.source)
    return problems


@dataclass(frozen=True)
class _Sweep:
    """A box of the gripper swept over a rectangle of the table plane: centre, the unit axis it
    is `along` with its half-length, the half-width across, and its lowest point."""

    centre: tuple[float, float]
    axis: tuple[float, float]
    half_along: float
    half_across: float
    bottom: float
    part: str

    def gap(self, world: World, body: str) -> float:
        """The horizontal clearance between this footprint and `body`'s (negative: overlap).
        A bowl the footprint reaches into (its centre inside the walls) is its walls' inside,
        a polygon of BOWL_SEGMENTS faces: every corner must stay inside each face."""
        pose, spec = world.poses[body], world.bodies[body]
        hx, hy = spec.half_extents[:2]
        if spec.kind == "bowl" and math.dist(self.centre, (pose.x, pose.y)) < hx - BOWL_WALL:
            corners = [(pose.x - x, pose.y - y) for x, y in self._corners()]
            return min((hx - BOWL_WALL) - (cx * math.cos(angle) + cy * math.sin(angle))
                       for cx, cy in corners for angle in _BOWL_FACES)
        if spec.kind in ROUND + ("bowl",):
            return self._distance_to(pose.x, pose.y, hx)
        ux, uy = self.axis
        vx, vy = -uy, ux
        dx, dy = pose.x - self.centre[0], pose.y - self.centre[1]
        gaps = []
        for nx, ny in ((1.0, 0.0), (0.0, 1.0), (ux, uy), (vx, vy)):
            mine = self.half_along * abs(ux * nx + uy * ny) + self.half_across * abs(vx * nx
                                                                                     + vy * ny)
            gaps.append(abs(dx * nx + dy * ny) - mine - hx * abs(nx) - hy * abs(ny))
        return max(gaps)

    def _corners(self) -> list[tuple[float, float]]:
        ux, uy = self.axis
        return [(self.centre[0] + a * ux - b * uy, self.centre[1] + a * uy + b * ux)
                for a in (-self.half_along, self.half_along)
                for b in (-self.half_across, self.half_across)]

    def _local(self, x: float, y: float) -> tuple[float, float]:
        dx, dy = x - self.centre[0], y - self.centre[1]
        ux, uy = self.axis
        return dx * ux + dy * uy, -dx * uy + dy * ux

    def _distance_to(self, x: float, y: float, radius: float) -> float:
        a, b = self._local(x, y)
        qa, qb = abs(a) - self.half_along, abs(b) - self.half_across
        if qa <= 0 and qb <= 0:
            return max(qa, qb) - radius
        return math.hypot(max(qa, 0.0), max(qb, 0.0)) - radius


def _grasp_sweeps(world: World, step: Step) -> list[_Sweep]:
    """Where the gripper comes down for a step: open around the source for a pick or place
    (straight down, fingers closing along x), closed behind it and along the push for a push
    (plans.py, push_points)."""
    if step.action != "push":
        pose = world.poses[step.source]
        centre, z = (pose.x, pose.y), pose.z
        return [_Sweep(centre, (1.0, 0.0), OPEN_FINGER_REACH, workspace.FINGER_WIDTH / 2,
                       z - workspace.FINGERTIP_DEPTH, "open fingers"),
                _Sweep(centre, (1.0, 0.0), *workspace.PALM_HALF, z + workspace.PALM_RISE,
                       "palm")]
    source, target = world.poses[step.source], world.poses[step.target]
    points = {p.name: p for p in push_points(world, step.arm or "left", step.source,
                                             (target.x - source.x, target.y - source.y))}
    start, end = points["push_start"].position, points["push_end"].position
    length = math.dist(start[:2], end[:2])
    along = ((end[0] - start[0]) / length, (end[1] - start[1]) / length) if length else (1, 0)
    centre = ((start[0] + end[0]) / 2, (start[1] + end[1]) / 2)
    # the closing axis lies across the push: the closed fingers are two thicknesses wide there
    return [_Sweep(centre, along, length / 2 + workspace.FINGER_WIDTH / 2,
                   workspace.FINGER_THICKNESS, start[2] - workspace.FINGERTIP_DEPTH,
                   "closed fingers"),
            _Sweep(centre, along, length / 2 + workspace.PALM_HALF[1], workspace.PALM_HALF[0],
                   start[2] + workspace.PALM_RISE, "palm")]


def _struck(world: World, sweep: _Sweep, body: str) -> float | None:
    """The clearance between `sweep` and `body` where the gripper part comes down low enough to
    meet the body (None: it stays above it). Inside a bowl, below its floor's top is a strike."""
    if sweep.bottom >= world.top(body):
        return None
    gap = sweep.gap(world, body)
    floor = world.bottom(body) + BOWL_FLOOR
    if world.bodies[body].kind == "bowl" and sweep.bottom < floor and (
            gap < 0 or math.dist(sweep.centre, (world.poses[body].x, world.poses[body].y))
            < world.bodies[body].half_extents[0]):
        return min(gap, sweep.bottom - floor)
    return gap


def _needed(world: World, body: str) -> float:
    """The least clearance from `body`: FINGER_MARGIN from what the fingers could move; a
    fixture cannot be knocked over, so fingers landing FINGER_MARGIN off may touch it (measured:
    an overlap up to 1.5 mm with a cube only nudges it; the grasp survives)."""
    return -FINGER_MARGIN if world.bodies[body].fixture else FINGER_MARGIN


def _clearance(behaviour: Behaviour, world: World) -> list[str]:
    """Steps whose gripper, coming down to grasp or push, would strike another body: the
    footprints at each jitter extreme (jitter_cases), with the bodies earlier steps moved left
    out."""
    problems = []
    for index, step in enumerate(behaviour.steps):
        earlier = behaviour.steps[:index]
        moved = frozenset({s.source for s in earlier} | {b for s in earlier
                                                         for b in world.carried_by(s.source)})
        for problem in _step_clearance(world, step, moved):
            problems.append(f"step {index + 1} ({describe_steps((step,))}): {problem}")
    return problems


_CACHE: dict[int, tuple[object, dict]] = {}  # id(scene) -> (scene, {key: value}), kept small


def _memo(world: World, key: tuple, make):
    """make(), remembered per scene (the entry holds the scene, so its id stays its own)."""
    scene = world.scene
    if id(scene) not in _CACHE:
        if len(_CACHE) >= 8:
            _CACHE.pop(next(iter(_CACHE)))
        _CACHE[id(scene)] = (scene, {})
    values = _CACHE[id(scene)][1]
    if key not in values:
        values[key] = make()
    return values[key]


def _step_clearance(world: World, step: Step, moved: frozenset[str]) -> list[str]:
    layout = world.layout.name
    cases = _memo(world, ("cases", layout), lambda: jitter_cases(world.scene, layout))
    key = ("clearance", layout, step.action, step.source,
           step.target if step.action == "push" else None, step.arm, moved)
    return _memo(world, key, lambda: _struck_bodies(world, cases, step, moved))


def _struck_bodies(world: World, cases: list, step: Step, moved: frozenset[str]) -> list[str]:
    skip = moved | {step.source} | set(world.carried_by(step.source))
    others = [b for b in world.bodies if b not in skip]
    worst: dict[tuple[str, str], tuple[float, int]] = {}
    for case, (_, case_world) in enumerate(cases):
        for sweep in _grasp_sweeps(case_world, step):
            reach = math.hypot(sweep.half_along, sweep.half_across) + 2 * FINGER_MARGIN
            for body in others:
                pose, half = case_world.poses[body], case_world.bodies[body].half_extents
                if math.dist(sweep.centre, (pose.x, pose.y)) > reach + math.hypot(*half[:2]):
                    continue
                gap = _struck(case_world, sweep, body)
                key = (sweep.part, body)
                if gap is not None and gap < _needed(world, body) and (
                        key not in worst or gap < worst[key][0]):
                    worst[key] = (gap, case)
    problems = []
    for (part, body), (gap, case) in worst.items():
        need = _needed(world, body)
        where = ("at the nominal positions" if case == 0
                 else f"at jitter extreme {case} ({cases[case][0]})")
        how = (f"sweep {100 * -gap:.1f} cm into {body}" if gap < 0
               else f"pass {100 * gap:.1f} cm from {body}")
        allowed = (f"{100 * need:.1f} cm clear" if need > 0
                   else f"at most {100 * -need:.1f} cm overlap with a fixture")
        problems.append(f"the {step.arm or '?'} arm's {part} {how} {where} ({allowed} "
                        "needed)")
    return problems
