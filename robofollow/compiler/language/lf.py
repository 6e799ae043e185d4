"""Logical forms: what an instruction means, as typed, frozen, canonical values.

Canonical by construction: a referring expression's constraints and a route's waypoints are
sets (sorted and deduplicated whenever a value is built), so two phrasings with one meaning
build equal values and byte-identical JSON.

Referring expressions nest one level: a relation's landmark ("the block to the right of *the
red ball*") is described by its own words only (colour, size, extremes, negations), never by a
further relation. A destination or push target may carry relations ("behind the block that is
to the left of the green ball").
"""

from __future__ import annotations

from typing import Annotated, Literal, Union, get_args

from pydantic import BaseModel, ConfigDict, Field, TypeAdapter, field_validator

Noun = Literal["object", "block", "cube", "cylinder", "sphere", "slab", "bowl", "label", "table"]
Color = Literal["red", "green", "blue", "yellow", "orange", "purple", "pink", "white", "black",
                "gray", "brown"]
Size = Literal["larger", "smaller"]
Extreme = Literal["leftmost", "rightmost", "frontmost", "backmost"]
Relation = Literal["left_of", "right_of", "in_front_of", "behind", "on", "in", "next_to",
                   "touching", "above", "below"]
PlaceRelation = Literal["left_of", "right_of", "in_front_of", "behind", "on", "in", "next_to"]
Arm = Literal["left", "right"]
Side = Literal["short", "long"]
Facing = Literal["front", "back", "left", "right"]
Nearness = Literal["nearest", "farthest"]


class Node(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


# ---------------------------------------------------------------- referring expressions
class ColorIs(Node):
    type: Literal["color"] = "color"
    color: Color
    negated: bool = False


class SizeIs(Node):
    """Comparative size among the candidates that match the rest of the description."""

    type: Literal["size"] = "size"
    size: Size


class ExtremeIs(Node):
    """Leftmost / rightmost / ... among the candidates that match the rest of the description."""

    type: Literal["extreme"] = "extreme"
    extreme: Extreme
    negated: bool = False


class NotKind(Node):
    """'that is not a cube'. A positive kind is the noun itself."""

    type: Literal["not_kind"] = "not_kind"
    noun: Noun


class OrdinalIs(Node):
    """'the second cube from the left': the rank-th of the candidates counted from a side."""

    type: Literal["ordinal"] = "ordinal"
    rank: int = Field(ge=1, le=5)
    side: Facing


class MiddleIs(Node):
    """'the middle cube': the one with as many candidates to its left as to its right."""

    type: Literal["middle"] = "middle"


def _simple_landmark(landmark: Ref) -> Ref:
    if not landmark.is_simple:
        raise ValueError("this landmark cannot itself be described by a relation")
    return landmark


class Related(Node):
    type: Literal["relation"] = "relation"
    relation: Relation
    landmark: Ref
    negated: bool = False

    _landmark_is_simple = field_validator("landmark")(_simple_landmark)


class Between(Node):
    """'between the red ball and the bowl' (the landmarks are a set)."""

    type: Literal["between"] = "between"
    landmarks: tuple[Ref, Ref]
    negated: bool = False

    @field_validator("landmarks")
    @classmethod
    def _canonical_pair(cls, landmarks: tuple) -> tuple:
        for landmark in landmarks:
            _simple_landmark(landmark)
        pair = _canonical_set(landmarks)
        if len(pair) != 2:
            raise ValueError("'between' needs two different landmarks")
        return pair


class NearestIs(Node):
    """'closest to the bowl' / 'farthest from the bowl' among the other candidates."""

    type: Literal["nearest"] = "nearest"
    nearness: Nearness
    landmark: Ref
    negated: bool = False

    _landmark_is_simple = field_validator("landmark")(_simple_landmark)


Constraint = Annotated[Union[ColorIs, SizeIs, ExtremeIs, NotKind, Related, Between, NearestIs,
                             OrdinalIs, MiddleIs],
                       Field(discriminator="type")]

# comparatives (size ... middle) apply in this order, among what the others leave
_CONSTRAINT_ORDER = {"color": 0, "size": 1, "extreme": 2, "not_kind": 3, "relation": 4,
                     "between": 5, "nearest": 6, "ordinal": 7, "middle": 8}
COMPARATIVES = (SizeIs, ExtremeIs, NearestIs, OrdinalIs, MiddleIs)
_POSITIONS = (OrdinalIs, MiddleIs)


def _canonical_set(items: tuple, order=lambda item: 0) -> tuple:
    """Sort and deduplicate by canonical JSON, so equal sets give equal tuples."""
    if len(items) < 2:
        return tuple(items)
    unique = {item.model_dump_json(): item for item in items}
    return tuple(unique[key] for key in sorted(unique, key=lambda k: (order(unique[k]), k)))


class Ref(Node):
    """A referring expression: a noun and a conjunction of constraints."""

    noun: Noun
    constraints: tuple[Constraint, ...] = ()

    @field_validator("constraints")
    @classmethod
    def _canonical(cls, constraints: tuple) -> tuple:
        if sum(isinstance(c, _POSITIONS) for c in constraints) > 1:
            raise ValueError("one description takes at most one ordinal or 'middle'")
        return _canonical_set(constraints, lambda c: _CONSTRAINT_ORDER[c.type])

    @property
    def is_simple(self) -> bool:
        """Described by its own words only (no other object named)."""
        return not any(isinstance(c, (Related, Between, NearestIs)) for c in self.constraints)


Related.model_rebuild()
Between.model_rebuild()
NearestIs.model_rebuild()


# ---------------------------------------------------------------- actions
class Placement(Node):
    relation: PlaceRelation
    landmark: Ref


class Waypoint(Node):
    """A route constraint: carry the object over ("via") or not over ("avoid") a landmark."""

    mode: Literal["via", "avoid"]
    landmark: Ref

    _landmark_is_simple = field_validator("landmark")(_simple_landmark)


class Orientation(Node):
    """Final orientation: 'with the <side> side facing <facing>'."""

    side: Side
    facing: Facing


class Pick(Node):
    type: Literal["pick"] = "pick"
    arm: Arm | None = None
    object: Ref


class Place(Node):
    type: Literal["place"] = "place"
    arm: Arm | None = None
    object: Ref
    destination: Placement
    route: tuple[Waypoint, ...] = ()
    orientation: Orientation | None = None

    @field_validator("route")
    @classmethod
    def _canonical_route(cls, route: tuple) -> tuple:
        route = _canonical_set(route)
        if len({w.landmark for w in route}) != len(route):
            raise ValueError("a route cannot both pass over and avoid one landmark")
        return route


class Push(Node):
    type: Literal["push"] = "push"
    arm: Arm | None = None
    object: Ref
    toward: Ref


Command = Annotated[Union[Pick, Place, Push], Field(discriminator="type")]


class Sequence(Node):
    """Commands done in order."""

    type: Literal["sequence"] = "sequence"
    steps: tuple[Command, ...] = Field(min_length=2)


Body = Annotated[Union[Pick, Place, Push, Sequence], Field(discriminator="type")]


# ---------------------------------------------------------------- conditions
class Exists(Node):
    """'there is an object in the bowl' (negated: 'the bowl is empty')."""

    type: Literal["exists"] = "exists"
    ref: Ref
    negated: bool = False


class Holds(Node):
    """'the blue sphere is (not) to the right of the red sphere': a property of one referent."""

    type: Literal["holds"] = "holds"
    subject: Ref
    property: Constraint


Condition = Annotated[Union[Exists, Holds], Field(discriminator="type")]


class Conditional(Node):
    type: Literal["conditional"] = "conditional"
    condition: Condition
    then: Body
    otherwise: Body | None = None


Instruction = Annotated[Union[Pick, Place, Push, Sequence, Conditional],
                        Field(discriminator="type")]

_INSTRUCTION = TypeAdapter(Instruction)


def to_json(lf: Instruction, indent: int | None = None) -> str:
    """Canonical JSON: the same meaning always gives the same bytes."""
    return lf.model_dump_json(indent=indent)


_CONSTRAINT_TYPES = get_args(get_args(Constraint)[0])  # the members of the Constraint union


def commands(form: Instruction) -> list[tuple[str, Pick | Place | Push]]:
    """(path, command) for every command of a form; the path names where it sits: "" (the
    form itself), "step<i>", "then.<path>", "otherwise.<path>"."""
    if isinstance(form, Conditional):
        found = [(f"then.{p}", c) for p, c in commands(form.then)]
        if form.otherwise is not None:
            found += [(f"otherwise.{p}", c) for p, c in commands(form.otherwise)]
        return found
    if isinstance(form, Sequence):
        return [(f"step{i}", c) for i, c in enumerate(form.steps)]
    return [("", form)]


def constructs(node) -> set[str]:
    """The kinds of description a form uses: constraint types, and 'relation:<name>' for each
    relation (what a wording generator may reuse)."""
    found: set[str] = set()
    if isinstance(node, tuple):
        for item in node:
            found |= constructs(item)
    elif isinstance(node, BaseModel):
        if isinstance(node, Related):
            found.add(f"relation:{node.relation}")
        if isinstance(node, _CONSTRAINT_TYPES):
            found.add(node.type)
        for name in type(node).model_fields:
            found |= constructs(getattr(node, name))
    return found


def from_json(data: str | bytes) -> Instruction:
    """Read a logical form back from JSON (validated, canonicalised)."""
    return _INSTRUCTION.validate_json(data)


def from_dict(data: dict) -> Instruction:
    return _INSTRUCTION.validate_python(data)

