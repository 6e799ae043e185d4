"""Logical form + layout -> Behaviour: which arm does what, to which object, where.

Referring expressions resolve against a World by geometry: first the plain constraints (noun,
colour, kind, relations), then the comparatives (larger / smaller, leftmost / ...) among what
is left, each of which must lead the runner-up by a named margin. No referent, or a tie, is a
GroundingError that lists the candidates.
"""

from __future__ import annotations

from dataclasses import dataclass

from pydantic import BaseModel

from robofollow.compiler.language import lf, notation
from robofollow.compiler.scene.behaviour import Behaviour, Step
from robofollow.compiler.scene.world import (
    DIRECTION_MARGIN_DEG,
    DIRECTIONS,
    EXTREME_AXES,
    EXTREME_MARGIN,
    NEAREST_MARGIN,
    ORDINAL_AXES,
    ORDINAL_MARGIN,
    RELATION_CONE_DEG,
    SIZE_MARGIN,
    World,
)
from robofollow.errors import RoboFollowError

TABLE = "table"  # the table as a landmark ('not touching the table')


class GroundingError(RoboFollowError):
    """An instruction that does not pick out one behaviour in a layout."""

    def __init__(self, code: str, message: str, candidates: tuple[str, ...] = (),
                 ref: lf.Ref | None = None):
        super().__init__(message)
        self.code = code
        self.message = message
        self.candidates = candidates
        self.ref = ref  # the description that failed, when one did


class Unclear(GroundingError):
    """A body near a direction's edge: a viewer cannot tell whether the relation holds."""


def kind_matches(world: World, body: str, noun: str) -> bool:
    """Whether a body can be called by a noun ("object" is any body, fixtures included)."""
    if body == TABLE:
        return noun == TABLE
    spec = world.bodies[body]
    if noun == "object":
        return True
    if noun == "block":
        return spec.kind in ("cube", "slab")
    return spec.kind == noun


def _describe(ref: lf.Ref) -> str:
    return notation.ref(ref)


class Grounder:
    """Grounds logical forms in one world."""

    def __init__(self, world: World, still: dict | None = None):
        """`still`: the memo of descriptions that read no position, shared by the grounders
        of one layout's jittered worlds."""
        self.world = world
        # keyed by object identity (cheap, unlike hashing nested models); the entry keeps its
        # description alive so that an id is never reused while cached
        self._referents: dict[int, tuple[lf.Ref, tuple[str, ...]]] = {}
        self._still: dict[int, tuple[lf.Ref, tuple[str, ...]]] = {} if still is None else still
        self._domains: dict[str, tuple[str, ...]] = {}

    # ---------------------------------------------------------------- referents
    def domain(self, noun: str) -> list[str]:
        """The bodies a noun can name (memoised)."""
        if noun not in self._domains:
            self._domains[noun] = ((TABLE,) if noun == TABLE else
                                   tuple(b for b in self.world.bodies
                                         if kind_matches(self.world, b, noun)))
        return list(self._domains[noun])

    def referents(self, ref: lf.Ref) -> list[str]:
        """Every body the description, said with 'the', can mean (memoised: a world does not
        change): of several in its direction, the one squarely there (`squarely`), even where
        the others stand near the direction's edge; else such a body makes it ambiguous."""
        cached = self._referents.get(id(ref))
        if cached is None or cached[0] is not ref:
            cached = self._still.get(id(ref))
            if cached is None or cached[0] is not ref:
                cached = (ref, tuple(self._definite(ref)))
                if _reads_no_position(ref):
                    self._still[id(ref)] = cached
            self._referents[id(ref)] = cached
        return list(cached[1])

    def _definite(self, ref: lf.Ref) -> list[str]:
        clear, unclear = self._sorted(ref)
        if any(isinstance(c, lf.COMPARATIVES) for c in ref.constraints):
            return self.fitting(ref, (clear, unclear))
        chosen = self.squarely([*clear, *unclear], ref)
        if len(chosen) == 1 and chosen[0] in clear:
            return chosen
        if unclear:
            raise next(iter(unclear.values()))
        return clear

    def fitting(self, ref: lf.Ref, sorted_: tuple | None = None) -> list[str]:
        """Every body the description fits ('there is a cube to the left of the bowl'); where
        none clearly does but one stands near a direction's edge, or a comparative would
        choose among them, it is ambiguous."""
        clear, unclear = sorted_ or self._sorted(ref)
        comparatives = [c for c in ref.constraints if isinstance(c, lf.COMPARATIVES)]
        if unclear and (comparatives or not clear):
            raise next(iter(unclear.values()))
        for constraint in comparatives:
            clear = self.compare(clear, constraint, ref)
        return clear

    def _sorted(self, ref: lf.Ref) -> tuple[list[str], dict[str, Unclear]]:
        """The bodies that fit every plain constraint, and those that fit all but stand near
        a direction's edge (with why)."""
        plain = [c for c in ref.constraints if not isinstance(c, lf.COMPARATIVES)]
        clear, unclear = [], {}
        for body in self.domain(ref.noun):
            try:
                if self._fits(body, plain):
                    clear.append(body)
            except Unclear as error:
                unclear[body] = Unclear("ambiguous", f"{_describe(ref)}: {error.message}",
                                        (body,), ref)
        return clear, unclear

    def _fits(self, body: str, constraints: list[lf.Constraint]) -> bool:
        """Whether a body fits every constraint (Unclear where the only doubt is a direction's
        edge)."""
        unclear = None
        for constraint in constraints:
            try:
                if not self.satisfies(body, constraint):
                    return False
            except Unclear as error:
                unclear = error
        if unclear is not None:
            raise unclear
        return True

    def resolve(self, ref: lf.Ref) -> str:
        """The one body a description picks out."""
        found = self.referents(ref)
        if not found:
            raise GroundingError("no-referent", f"nothing in layout {self.world.layout.name} "
                                                f"is {_describe(ref)}", ref=ref)
        if len(found) > 1:
            raise GroundingError("ambiguous", f"{_describe(ref)} could be any of "
                                              f"{', '.join(found)} in layout "
                                              f"{self.world.layout.name}", tuple(found), ref)
        return found[0]

    def satisfies(self, body: str, constraint: lf.Constraint) -> bool:
        if body == TABLE:
            return False
        if isinstance(constraint, lf.ColorIs):
            return (self.world.bodies[body].color == constraint.color) != constraint.negated
        if isinstance(constraint, lf.NotKind):
            return not kind_matches(self.world, body, constraint.noun)
        if isinstance(constraint, lf.Between):
            a, b = (self.resolve(landmark) for landmark in constraint.landmarks)
            holds = body not in (a, b) and TABLE not in (a, b) and self.world.between(body, a, b)
            return holds != constraint.negated
        if isinstance(constraint, lf.Related):
            landmark = self.resolve(constraint.landmark)
            if landmark == body:
                return False
            relation = constraint.relation
            if landmark == TABLE:
                relation = "touching" if relation in ("on", "touching") else relation
                holds = relation == "touching" and self.world.related(body, relation, TABLE)
            elif relation in DIRECTIONS:
                holds = self.direction(body, relation, landmark)
            else:
                holds = self.world.related(body, relation, landmark)
            return holds != constraint.negated
        # a comparative on one body: is it the extreme among the bodies of its kind?
        return body in self.compare(self.domain(self._noun_of(body)), constraint, None)

    def squarely(self, found: list[str], ref: lf.Ref) -> list[str]:
        """Of several bodies in a description's direction ("the block to the right of the red
        ball"), the one a viewer takes: no less square to the direction and no farther than
        each other, and ahead by DIRECTION_MARGIN_DEG or NEAREST_MARGIN, for every direction
        the description names; else all."""
        directions = [c for c in ref.constraints if isinstance(c, lf.Related)
                      and c.relation in DIRECTIONS and not c.negated]
        if len(found) < 2 or not directions:
            return found
        views = []
        for constraint in directions:
            landmark = self.resolve(constraint.landmark)
            views.append({b: (self.world.off_axis(b, constraint.relation, landmark),
                              self.world.distance(b, landmark)) for b in found})
        for body in found:
            if all(_ahead(view[body], view[other]) for view in views
                   for other in found if other != body):
                return [body]
        return found

    def direction(self, body: str, relation: str, landmark: str) -> bool:
        """Whether `body <relation> landmark` holds as a viewer sees it: within
        RELATION_CONE_DEG of the direction at any distance. Within DIRECTION_MARGIN_DEG of
        that edge it is Unclear."""
        angle = self.world.off_axis(body, relation, landmark)
        if angle is None:
            return False
        if abs(angle - RELATION_CONE_DEG) < DIRECTION_MARGIN_DEG:
            raise Unclear("ambiguous", f"{body} stands {angle:.0f}° off the {relation} direction "
                                       f"of {landmark}, too near the {RELATION_CONE_DEG:.0f}° edge "
                                       "to tell", (body,))
        return angle < RELATION_CONE_DEG

    def _noun_of(self, body: str) -> str:
        return self.world.bodies[body].kind

    def compare(self, candidates: list[str], constraint, ref: lf.Ref | None) -> list[str]:
        """Apply 'larger', 'leftmost', 'closest to X', 'second from the left', 'middle' (and
        negations) to a candidate list: the winner must lead by the named margin."""
        if isinstance(constraint, lf.NearestIs):
            landmark = self.resolve(constraint.landmark)
            candidates = [b for b in candidates if b != landmark]
        if isinstance(constraint, (lf.OrdinalIs, lf.MiddleIs)):
            return self.position(candidates, constraint, ref)
        if len(candidates) <= 1:
            return [] if getattr(constraint, "negated", False) else candidates
        if isinstance(constraint, lf.SizeIs):
            sign = 1.0 if constraint.size == "larger" else -1.0
            values = {b: sign * self.world.bodies[b].volume for b in candidates}
            ranked = sorted(candidates, key=lambda b: -values[b])
            best, second = values[ranked[0]], values[ranked[1]]
            if abs(best - second) < SIZE_MARGIN * max(abs(best), abs(second)):
                self._tie(ranked[:2], constraint, ref)
            return ranked[:1]
        if isinstance(constraint, lf.NearestIs):
            sign = -1.0 if constraint.nearness == "nearest" else 1.0
            values = {b: sign * self.world.distance(b, landmark) for b in candidates}
            margin = NEAREST_MARGIN
        else:
            axis, sign = EXTREME_AXES[constraint.extreme]
            values = {b: sign * (self.world.poses[b].x, self.world.poses[b].y)[axis]
                      for b in candidates}
            margin = EXTREME_MARGIN
        ranked = sorted(candidates, key=lambda b: -values[b])
        if values[ranked[0]] - values[ranked[1]] < margin:
            self._tie(ranked[:2], constraint, ref)
        return ranked[1:] if constraint.negated else ranked[:1]

    def position(self, candidates: list[str], constraint, ref: lf.Ref | None) -> list[str]:
        """The rank-th candidate counted from a side, or the middle one (left to right); its
        neighbours in the count must stand ORDINAL_MARGIN clear of it."""
        axis, sign = ORDINAL_AXES[getattr(constraint, "side", "left")]
        values = {b: sign * (self.world.poses[b].x, self.world.poses[b].y)[axis]
                  for b in candidates}
        ranked = sorted(candidates, key=lambda b: values[b])
        if isinstance(constraint, lf.MiddleIs):
            if len(ranked) % 2 == 0:
                if ranked:
                    raise GroundingError("ambiguous", f"no single middle one among "
                                                      f"{len(ranked)}: {', '.join(ranked)}",
                                         tuple(ranked), ref)
                return []
            index = len(ranked) // 2
        else:
            index = constraint.rank - 1
            if index >= len(ranked):
                return []
        chosen = ranked[index]
        for neighbour in ranked[max(index - 1, 0):index + 2]:
            if neighbour != chosen and abs(values[neighbour] - values[chosen]) < ORDINAL_MARGIN:
                self._tie([chosen, neighbour], constraint, ref)
        return [chosen]

    def _tie(self, tied: list[str], constraint, ref: lf.Ref | None) -> None:
        if getattr(constraint, "negated", False):
            constraint = constraint.model_copy(update={"negated": False})
        word = notation.constraint(constraint)
        raise GroundingError("ambiguous", f"no single {word} one: {', '.join(tied)} are within "
                                          "tolerance of each other", tuple(tied), ref)

    # ---------------------------------------------------------------- conditions
    def holds(self, condition: lf.Condition) -> bool:
        if isinstance(condition, lf.Exists):
            return bool(self.fitting(condition.ref)) != condition.negated
        return self.satisfies(self.resolve(condition.subject), condition.property)

    # ---------------------------------------------------------------- behaviour
    def behaviour(self, instruction: lf.Instruction, every_branch: bool = False) -> Behaviour:
        """The behaviour the words ask for here; `every_branch`: a conditional's branch not
        taken must ground too (else its GroundingError, said of that branch), as the rules
        of a test task ask: a careful reader reads both branches."""
        if not isinstance(instruction, lf.Conditional):
            return Behaviour(steps=self.steps(instruction))
        truth = self.holds(instruction.condition)
        taken, other = ((instruction.then, instruction.otherwise) if truth
                        else (instruction.otherwise, instruction.then))
        try:
            other_steps = self.steps(other) if other is not None else ()
        except GroundingError as error:
            if every_branch:
                raise GroundingError(error.code, f"in the branch not taken "
                                     f"({'otherwise' if truth else 'then'}), {error.message}",
                                     error.candidates, error.ref) from None
            other_steps = None
        return Behaviour(steps=self.steps(taken) if taken is not None else (), condition=truth,
                         branch="then" if truth else "otherwise", other=other_steps)

    def steps(self, body: lf.Body) -> tuple[Step, ...]:
        if isinstance(body, lf.Sequence):
            return tuple(self.step(command) for command in body.steps)
        return (self.step(body),)

    def step(self, command: lf.Pick | lf.Place | lf.Push) -> Step:
        return Step(**self._step_fields(command))

    def objects(self, instruction: lf.Instruction) -> tuple[tuple[str, str | None], ...]:
        """The (source, target) of each step `behaviour` gives, failing as it fails, without
        building it (the jitter check asks this of many worlds)."""
        body = instruction
        if isinstance(instruction, lf.Conditional):
            body = instruction.then if self.holds(instruction.condition) else instruction.otherwise
            if body is None:
                return ()
        commands = body.steps if isinstance(body, lf.Sequence) else (body,)
        return tuple((fields["source"], fields.get("target"))
                     for fields in map(self._step_fields, commands))

    def _step_fields(self, command: lf.Pick | lf.Place | lf.Push) -> dict:
        """The fields of the Step a command grounds to."""
        source = self.resolve(command.object)
        if source == TABLE or self.world.bodies[source].fixture:
            raise GroundingError("unsupported", f"{source} is fixed and cannot be moved")
        if isinstance(command, lf.Pick):
            return {"action": "pick", "arm": command.arm, "source": source}
        if isinstance(command, lf.Push):
            return {"action": "push", "arm": command.arm, "source": source,
                    "target": self.resolve(command.toward)}
        target = self.resolve(command.destination.landmark)
        waypoints = tuple(sorted({(w.mode, self.resolve(w.landmark)) for w in command.route}))
        return {"action": "place", "arm": command.arm, "source": source,
                "relation": command.destination.relation, "target": target,
                "waypoints": waypoints, "yaw_degrees": self.yaw(source, command.orientation)}

    def yaw(self, body: str, orientation: lf.Orientation | None) -> float | None:
        """The final yaw (deg, modulo 180) that puts the named side the named way."""
        if orientation is None:
            return None
        hx, hy, _ = self.world.bodies[body].half_extents
        if abs(hx - hy) < 1e-6:
            raise GroundingError("unsupported", f"{body} has no long side to orient")
        long_axis_on_y = hy > hx  # at yaw 0
        facing_on_y = orientation.facing in ("front", "back")
        # the short sides face along the long axis; the long sides across it
        wants_long_axis_on_y = facing_on_y == (orientation.side == "short")
        return 0.0 if wants_long_axis_on_y == long_axis_on_y else 90.0


def _ahead(seen: tuple[float, float], other: tuple[float, float]) -> bool:
    """Whether a body seen at (angle off a direction, distance) is the one a viewer takes over
    another: no less square and no farther, and clearly ahead in one of them."""
    (angle, distance), (their_angle, their_distance) = seen, other
    return (angle <= their_angle and distance <= their_distance
            and (their_angle - angle >= DIRECTION_MARGIN_DEG
                 or their_distance - distance >= NEAREST_MARGIN))


@dataclass(frozen=True)
class Unstable:
    """The first jittered world where a form stops meaning what it means nominally."""
    case: int  # the world's number
    world: World
    error: GroundingError | None  # it does not ground there, or
    objects: tuple[tuple[str, str | None], ...] = ()  # the (source, target) it picks instead


_STILL = (lf.ColorIs, lf.NotKind, lf.SizeIs)  # constraints that read no position


def _reads_no_position(ref: lf.Ref) -> bool:
    """Whether a description picks the same bodies wherever the bodies stand."""
    return all(isinstance(c, _STILL) for c in ref.constraints)


def position_reads(node, grounder: Grounder) -> set[str]:
    """The bodies whose positions can change what `node` (a form or a part of one) picks out:
    the candidates and landmarks of each description that relates or compares positions (every
    body for a condition that does)."""
    found: set[str] = set()
    if isinstance(node, tuple):
        for item in node:
            found |= position_reads(item, grounder)
    elif isinstance(node, lf.Holds) and not isinstance(node.property, _STILL):
        found |= set(grounder.world.bodies)
    elif isinstance(node, BaseModel):
        if isinstance(node, lf.Ref) and not _reads_no_position(node):
            found.update(_eligible(node, grounder))
            for constraint in node.constraints:
                for landmark in _landmarks(constraint):
                    found.update(_eligible(landmark, grounder))
        for name in type(node).model_fields:
            found |= position_reads(getattr(node, name), grounder)
    return found


def _eligible(ref: lf.Ref, grounder: Grounder) -> list[str]:
    """The bodies a description could pick wherever bodies stand: its noun's, less those its
    colour and kind words rule out."""
    fixed = [c for c in ref.constraints if isinstance(c, (lf.ColorIs, lf.NotKind))]
    return [b for b in grounder.domain(ref.noun) if all(grounder.satisfies(b, c) for c in fixed)]


def _landmarks(constraint: lf.Constraint) -> tuple[lf.Ref, ...]:
    if isinstance(constraint, lf.Between):
        return constraint.landmarks
    landmark = getattr(constraint, "landmark", None)
    return () if landmark is None else (landmark,)


def first_unstable(form: lf.Instruction, grounders: list[Grounder], expected: Behaviour,
                   first_case: int = 0) -> Unstable | None:
    """The first of the worlds (numbered from `first_case`) where `form` fails to ground or
    picks other objects than `expected`; None when it means the same in all of them. Worlds
    where no body the form reads has moved give one verdict, asked once."""
    objects = tuple((s.source, s.target) for s in expected.steps)
    reads = position_reads(form, grounders[0]) if grounders else set()
    settled = False  # a world where nothing the form reads moved was found stable
    for index, grounder in enumerate(grounders, start=first_case):
        untouched = grounder.world.shifted.isdisjoint(reads)
        if untouched and settled:
            continue
        try:
            picked = grounder.objects(form)
        except GroundingError as error:
            return Unstable(index, grounder.world, error)
        if picked != objects:
            return Unstable(index, grounder.world, None, picked)
        settled = settled or untouched
    return None


def instability(form: lf.Instruction, grounders: list[Grounder], expected: Behaviour,
                first_case: int = 0) -> str | None:
    """Why `form` fails to ground, or picks other objects than `expected`, in one of the
    worlds (numbered from `first_case`); None when it means the same in all of them."""
    unstable = first_unstable(form, grounders, expected, first_case)
    if unstable is None:
        return None
    if unstable.error is not None:
        return f"jitter case {unstable.case}: {unstable.error.code}: {unstable.error.message}"
    return f"jitter case {unstable.case} changes the objects it refers to"


def ground(instruction: lf.Instruction, world: World) -> Behaviour:
    """The behaviour an instruction asks for in a world."""
    return Grounder(world).behaviour(instruction)
