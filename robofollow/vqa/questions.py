"""Questions about a layout, answered by the compiler's grounding.

A question is an `Ask` (what is asked, as data) put into words. Its answer is found exactly as
an instruction's referents are: the same relations, cones, ranges and margins (world.py), on
the world the image shows (after jitter). A question is kept only when its answer is unique:
one referent, extremes and sides clear by the grounding's margin. In questions "object" names
anything on the table, bowls and labels included.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from dataclasses import dataclass

from robofollow.compiler.language import lf
from robofollow.compiler.scene.grounding import Grounder, GroundingError
from robofollow.compiler.scene.model import Model
from robofollow.compiler.scene.world import EXTREME_MARGIN, World
from robofollow.vqa.answers import KIND_WORDS, Expected, Named, named, side_words

RELATION_WORDS = {"left_of": "to the left of", "right_of": "to the right of",
                  "behind": "behind", "in_front_of": "in front of", "in": "in",
                  "on": "on top of"}
SIDE_RELATIONS = {"left": "left_of", "right": "right_of"}
EXTREMES = ("leftmost", "rightmost")
MAX_GROUP = 3  # objects a "which are the red objects" question may list


class Question(Model):
    id: str
    template: str
    question: str
    answer: str  # the reference answer in words
    expected: Expected


@dataclass(frozen=True)
class Ask:
    """What a question asks. `template`:
    color        the colour of the `noun` at `relation` to `landmark`
    what         what the object at `relation` to `landmark` is
    describe     what it is and its colour
    which_side   which object is on the `side` side of `landmark`
    extreme      the colour of the `extreme` `noun`
    pair         which of the two `noun`s / `color` objects is on the left and the right
    relative     where the two `noun`s are relative to each other, which is on the left
    property     the `color` objects and their positions
    """
    template: str
    relation: str | None = None
    landmark: lf.Ref | None = None
    noun: str = "object"
    extreme: str | None = None
    color: str | None = None


def plural(noun: str) -> str:
    return KIND_WORDS.get(noun, noun) + "s"


def landmark_words(ref: lf.Ref) -> str:
    colors = [c.color for c in ref.constraints if isinstance(c, lf.ColorIs)]
    return " ".join([*colors, KIND_WORDS.get(ref.noun, ref.noun)])


def wording(ask: Ask) -> str:
    """The question in words."""
    if ask.template in ("color", "what", "describe", "which_side"):
        place = f"{RELATION_WORDS[ask.relation]} the {landmark_words(ask.landmark)}"
        if ask.template == "color":
            return f"Output the color of the {ask.noun} {place}."
        if ask.template == "what":
            return f"What is the object {place}?"
        if ask.template == "describe":
            return (f"Describe the object {place}, such as what it is and what color it is.")
        side = "left" if ask.relation == "left_of" else "right"
        return (f"Which object is located on the {side} side of the "
                f"{landmark_words(ask.landmark)}?")
    if ask.template == "extreme":
        return f"Output the color of the {ask.extreme} {KIND_WORDS.get(ask.noun, ask.noun)}."
    group = f"{ask.color} objects" if ask.color else plural(ask.noun)
    if ask.template == "pair":
        return (f"Looking at the two {group} on the table, which one is on the left and which "
                "one is on the right?")
    if ask.template == "relative":
        noun = KIND_WORDS.get(ask.noun, ask.noun)
        return (f"Where are the two {group} located relative to each other? Which {noun} is "
                "on the left side?")
    return f"What are the {group} in the scene, and what are their positions?"


def referents(grounder: Grounder, ask: Ask) -> list[str]:
    """Every body the question could be about (one, unless it is ambiguous here); for the
    group questions, the group from left to right."""
    world = grounder.world
    if ask.template in ("color", "what", "describe", "which_side"):
        return grounder.referents(lf.Ref(noun=ask.noun, constraints=(
            lf.Related(relation=ask.relation, landmark=ask.landmark),)))
    if ask.template == "extreme":
        return grounder.referents(lf.Ref(noun=ask.noun,
                                         constraints=(lf.ExtremeIs(extreme=ask.extreme),)))
    members = [b for b in world.bodies if (world.bodies[b].color == ask.color if ask.color
                                           else world.bodies[b].kind == ask.noun)]
    return sorted(members, key=lambda b: world.poses[b].x)


def expected(world: World, ask: Ask, found: list[str]) -> Expected:
    context = {"template": ask.template, "question_names": () if ask.landmark is None else (
        Named(color=next(c.color for c in ask.landmark.constraints
                         if isinstance(c, lf.ColorIs)), kind=ask.landmark.noun),)}
    if ask.template in ("color", "extreme"):
        return Expected(type="color", color=world.bodies[found[0]].color, **context)
    if ask.template in ("what", "describe", "which_side"):
        return Expected(type="object", object=named(world, found[0]),
                        needs_color=ask.template == "describe", **context)
    return Expected(type="sides", objects=tuple(named(world, b) for b in found),
                    sides=side_words(len(found)), **context)


def unique_answer(grounder: Grounder, ask: Ask) -> Expected | None:
    """The answer, or None when the question has no single answer in this world."""
    try:
        found = referents(grounder, ask)
    except GroundingError:  # a landmark or an extreme that is not clear-cut
        return None
    if ask.template in ("pair", "relative", "property"):
        return expected(grounder.world, ask, found) if _clear_group(grounder.world, ask,
                                                                     found) else None
    return expected(grounder.world, ask, found) if len(found) == 1 else None


def _clear_group(world: World, ask: Ask, members: list[str]) -> bool:
    """Two (or, for 'property', up to three) members, told apart by their words, each clearly
    left of the next."""
    wanted = (2,) if ask.template in ("pair", "relative") else range(2, MAX_GROUP + 1)
    if len(members) not in wanted:
        return False
    words = {named(world, b) for b in members}
    xs = [world.poses[b].x for b in members]
    return len(words) == len(members) and all(b - a >= EXTREME_MARGIN
                                              for a, b in itertools.pairwise(xs))


def landmark_ref(grounder: Grounder, body: str) -> lf.Ref | None:
    """'the <colour> <kind>' for a body, if those words pick it out alone."""
    spec = grounder.world.bodies[body]
    ref = lf.Ref(noun=spec.kind, constraints=(lf.ColorIs(color=spec.color),))
    try:
        return ref if grounder.resolve(ref) == body else None
    except GroundingError:
        return None


def asks(world: World, grounder: Grounder) -> Iterator[Ask]:
    """Every question the templates can ask about a world, in a fixed order."""
    kinds = sorted({spec.kind for spec in world.bodies.values()})
    several = [k for k in kinds if sum(s.kind == k for s in world.bodies.values()) > 1]
    for body in world.bodies:
        landmark = landmark_ref(grounder, body)
        if landmark is None:
            continue
        for relation in RELATION_WORDS:
            for template in ("color", "what", "describe"):
                yield Ask(template, relation, landmark)
            if relation in SIDE_RELATIONS.values():
                yield Ask("which_side", relation, landmark)
            for noun in several:
                yield Ask("color", relation, landmark, noun=noun)
    for noun in several:
        for extreme in EXTREMES:
            yield Ask("extreme", noun=noun, extreme=extreme)
        yield Ask("pair", noun=noun)
        yield Ask("relative", noun=noun)
    for color in sorted({spec.color for spec in world.bodies.values()}):
        yield Ask("pair", color=color)
        yield Ask("property", color=color)


def questions(world: World) -> list[Question]:
    """The uniquely answerable questions about a world, each once, in a fixed order."""
    grounder = Grounder(world)
    found: dict[str, Question] = {}
    for ask in asks(world, grounder):
        answer = unique_answer(grounder, ask)
        text = wording(ask)
        if answer is None or text in found:
            continue
        found[text] = Question(id=f"{ask.template}-{len(found):03d}", template=ask.template,
                               question=text, answer=answer.text, expected=answer)
    return list(found.values())
