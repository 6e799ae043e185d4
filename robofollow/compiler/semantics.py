"""Syntax records -> canonical logical forms.

Decides what the grammar leaves open, by these documented rules:

* Modifier chains are flat: every link after an object describes that object, except
  - the destination of a transport verb (place/put/stack/move/take/remove): the *last*
    relation phrase after a noun phrase object, or the *first* one after 'it' (which takes no
    description); links after the destination describe the destination's landmark;
  - 'towards X' of push: links after it describe X;
  - route phrases ('over X', 'around X'), which constrain the carried object's path.
* Clauses group into steps: an action on 'it' (or 'that <noun>') continues the current step
  ("pick up X, pass over Y, then place it on Z" is one placement); an action on a new noun
  phrase starts a new step, and several steps make a sequence. 'A before B-ing' and
  'before B-ing, A' do A first; 'A after B-ing' and 'after B-ing, A' do B first.
* An arm phrase before the first action sets the arm of every step; 'use your left arm to'
  leads one action; elsewhere an arm phrase names the arm of the step it follows.
* 'it' in a route ("detour to avoid passing over it") is the route's last landmark; elsewhere
  it is the object being handled, or in a conditional branch, what the condition mentions.
* 'one' stands for the noun of 'among the <nouns>' (else 'object'); 'from/off X' means on X
  (in X for a container); positive 'is a <noun>' narrows the noun.
* 'over / above X' is a route after a transport verb; after 'pick up', in a relative clause
  and in a condition it describes an object (vertically above X). 'A and B' after a verb
  handles each object in turn, with the same destination, route and arm.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from pydantic import ValidationError

from robofollow.compiler import lf
from robofollow.compiler.syntax import (
    NP,
    PP,
    Action,
    Among,
    ArmPhrase,
    Break,
    ConditionalPhrase,
    ConditionPhrase,
    It,
    Link,
    OrientationPhrase,
    Predicate,
    Region,
    RoutePhrase,
    Steps,
)
from robofollow.errors import UnsupportedConstructError

_WORD = re.compile(r"[A-Za-z'’-]+")
_NOUN_PARENTS = {"cube": "block", "slab": "block"}
_CONTAINERS = frozenset({"bowl"})
_TRANSPORT_VERBS = frozenset({"place", "stack", "move", "take", "remove"})
_PICK_VERBS = frozenset({"pick", "grasp"})
# 'take X on Y' names where X is; 'take X onto / to Y' where it goes
_DESTINATION_KINDS = {"take": ("destination",)}
_DESTINATION_REQUIRED = frozenset({"place", "stack"})
_PLACE_RELATIONS = frozenset(lf.PlaceRelation.__args__)
_SIDE_RELATIONS = {"left": "left_of", "right": "right_of"}
_SIDE_EXTREMES = {"left": "leftmost", "right": "rightmost"}
_PARTICLES = {"up": ("pick", "grasp"), "down": ("place",)}  # particle -> verbs it goes with
_UNPLACEABLE = {"between": "between two objects", "above": "above an object (say 'on')",
                "below": "under an object", "touching": "touching an object"}

# (preposition, target shape) -> (meaning kind, relation or mode)
_NP_PREPOSITIONS = {
    "on": ("relation", "on"), "in": ("relation", "in"), "inside": ("relation", "in"),
    "behind": ("relation", "behind"), "beside": ("relation", "next_to"),
    "next_to": ("relation", "next_to"), "touching": ("relation", "touching"),
    "into": ("destination", "in"), "onto": ("destination", "on"), "to": ("destination", "on"),
    "from": ("source", None), "off": ("source", None), "out_of": ("source", "in"),
    "over": ("route", "via"), "via": ("route", "via"), "around": ("route", "avoid"),
    "towards": ("toward", None), "below": ("relation", "below"),
}
_REGION_PREPOSITIONS = {
    ("side", "on"): "extreme", ("side", "at"): "extreme",
    ("extreme_position", "in"): "extreme", ("extreme_position", "at"): "extreme",
    ("side_of", "to"): "relation", ("side_of", "on"): "relation", ("side_of", "at"): "relation",
    ("top_of", "on"): "relation", ("top_of", "onto"): "destination",
    ("top_of", "to"): "destination", ("top_of", "from"): "source", ("top_of", "off"): "source",
    ("front_of", "in"): "relation", ("front_of", "at"): "relation", ("front_of", "to"): "relation",
    ("direction_of", "in"): "toward",
    ("middle", "in"): "middle", ("middle", "at"): "middle",
    ("back_of", "at"): "relation", ("back_of", "in"): "relation", ("back_of", "to"): "relation",
    ("position", "at"): "position", ("position", "to"): "position", ("position", "in"): "position",
}


@dataclass(slots=True)
class Meaning:
    """What one link of a modifier chain says."""

    kind: str  # relation, destination, source, extreme, route, toward, constraint, noun, particle
    column: int
    relation: str | None = None
    landmark: lf.Ref | It | tuple[lf.Ref, lf.Ref] | None = None  # a pair for 'between'
    constraint: object = None
    noun: str | None = None
    negated: bool = False
    preposition: str | None = None  # as said, for a noun-phrase target


@dataclass(slots=True)
class Draft:
    """A step under construction."""

    object: lf.Ref
    column: int
    kind: str = "hold"  # hold (picked, maybe to be placed), place, push
    arm: str | None = None
    destination: lf.Placement | None = None
    toward: lf.Ref | None = None
    route: list[lf.Waypoint] = field(default_factory=list)
    route_column: int = 0
    orientation: lf.Orientation | None = None
    orientation_column: int = 0
    last_landmark: lf.Ref | None = None
    marker: str | None = None  # 'before' / 'after' <gerund>: order relative to its main clause
    shared: bool = False  # one of several objects named together ('A and B')


class Semantics:
    """One instruction's semantic pass (holds the text for error messages)."""

    def __init__(self, text: str):
        self.text = text
        self.domain: lf.Ref | None = None  # 'among the <nouns>': what a later 'one' stands for

    def fail(self, column: int, message: str) -> UnsupportedConstructError:
        return UnsupportedConstructError(message, text=self.text, column=column,
                                         length=self._word_length(column))

    def _word_length(self, column: int) -> int:
        word = _WORD.match(self.text, column - 1)
        return len(word.group()) if word else 1

    # ---------------------------------------------------------------- entry
    def instruction(self, syntax) -> lf.Instruction:
        if isinstance(syntax, ConditionalPhrase):
            return self.conditional(syntax)
        return self.steps(syntax, focus=None)

    def conditional(self, phrase: ConditionalPhrase) -> lf.Conditional:
        condition, entity = self.condition(phrase.condition)
        if phrase.negate_condition:
            condition = self.negate(condition, phrase.column)
        then = self.steps(phrase.then, focus=entity)
        otherwise = self.steps(phrase.otherwise, focus=entity) if phrase.otherwise else None
        return lf.Conditional(condition=condition, then=then, otherwise=otherwise)

    # ---------------------------------------------------------------- conditions
    def condition(self, phrase: ConditionPhrase) -> tuple[lf.Condition, lf.Ref]:
        if phrase.kind == "is" and phrase.subject.det in ("a", "no"):
            return self.indefinite(phrase)
        subject = self.describe(phrase.subject, self.meanings(phrase.chain, describing=True))
        if phrase.kind == "there_is":
            return lf.Exists(ref=subject, negated=phrase.negated), subject
        if phrase.kind in ("contains", "has_on_top"):
            relation = "in" if phrase.kind == "contains" else "on"
            content = self.describe(phrase.predicate, [
                Meaning("relation", phrase.column, relation, self.landmark(subject, phrase))])
            return lf.Exists(ref=content, negated=phrase.negated), content
        predicate = phrase.predicate
        if isinstance(predicate, Predicate) and predicate.kind == "empty":
            content = lf.Ref(noun="object", constraints=(
                lf.Related(relation="in", landmark=self.landmark(subject, phrase)),))
            claims_empty = not predicate.value
            return lf.Exists(ref=content, negated=claims_empty != phrase.negated), content
        meaning = self.predicate(predicate, phrase.negated, phrase.column)
        if meaning.kind == "noun" and predicate.kind in ("extreme", "ordinal", "size"):
            meaning = Meaning("constraint", meaning.column, constraint=meaning.constraint[0])
        if meaning.kind != "constraint":
            raise self.fail(phrase.column, "a condition can test a relation, colour, size or "
                                           "position of an object, not what kind it is")
        return lf.Holds(subject=subject, property=meaning.constraint), subject

    def indefinite(self, phrase: ConditionPhrase) -> tuple[lf.Condition, lf.Ref]:
        """'if an object is on the cube' = 'if there is an object on the cube' ('no object is
        ...': there is none)."""
        meaning = self.predicate(phrase.predicate, phrase.negated, phrase.column)
        if meaning.kind != "constraint":
            raise self.fail(phrase.column, "say 'if there is a <noun> ...'")
        meanings = self.meanings(phrase.chain, describing=True) + [meaning]
        ref = self.describe(phrase.subject, meanings)
        return lf.Exists(ref=ref, negated=phrase.subject.det == "no"), ref

    def landmark(self, ref: lf.Ref, phrase: ConditionPhrase) -> lf.Ref:
        if not ref.is_simple:
            raise self.fail(phrase.column, "describe this container without a relation "
                                           "(relations do not nest)")
        return ref

    def negate(self, condition: lf.Condition, column: int) -> lf.Condition:
        if isinstance(condition, lf.Exists):
            return condition.model_copy(update={"negated": not condition.negated})
        prop = condition.property
        if not hasattr(prop, "negated"):
            raise self.fail(column, "'unless' cannot negate this condition; use 'if'")
        flipped = prop.model_copy(update={"negated": not prop.negated})
        return lf.Holds(subject=condition.subject, property=flipped)

    # ---------------------------------------------------------------- steps
    def steps(self, steps: Steps, focus: lf.Ref | None) -> lf.Body:
        drafts: list[Draft] = []
        current: Draft | None = None
        default_arm: str | None = None
        fronted: list[RoutePhrase | OrientationPhrase] = []
        after_break = True
        segments = steps.segments
        for index, segment in enumerate(segments):
            following = segments[index + 1] if index + 1 < len(segments) else None
            if isinstance(segment, Break):
                after_break = True
                continue
            if isinstance(segment, Among):
                self.domain = lf.Ref(noun=segment.noun, constraints=tuple(
                    self.premod(p) for p in segment.premods))
            elif isinstance(segment, ArmPhrase):
                if current is None and not drafts:
                    default_arm = segment.side
                elif after_break and isinstance(following, Action):
                    if following.lead_arm is not None and following.lead_arm.side != segment.side:
                        raise self.fail(following.lead_arm.column, "two arms named for one action")
                    following.lead_arm = segment
                else:
                    self.set_arm(current, segment)
            elif isinstance(segment, Action):
                current, started = self.action(segment, current, focus)
                drafts.extend(started)
                focus = current.object
            elif isinstance(segment, (RoutePhrase, OrientationPhrase)) and current is None and \
                    isinstance(following, Action | Break) and not drafts:
                fronted.append(segment)  # 'Passing over X, move Y onto Z': for the first action
            elif isinstance(segment, RoutePhrase):
                self.route(segment, current)
            elif isinstance(segment, OrientationPhrase):
                self.orientation(segment, current)
            if fronted and current is not None:
                for phrase in fronted:
                    if isinstance(phrase, RoutePhrase):
                        self.route(phrase, current)
                    else:
                        self.orientation(phrase, current)
                fronted.clear()
            after_break = False
        if current is None:
            raise self.fail(steps.column, "no action: say what to do (pick up, place, push ...)")
        body = [self.command(draft, default_arm) for draft in self.ordered(drafts)]
        return body[0] if len(body) == 1 else lf.Sequence(steps=tuple(body))

    @staticmethod
    def ordered(drafts: list[Draft]) -> list[Draft]:
        """Text order, except 'A after B-ing' (B first) and 'before B-ing, A' (A first)."""
        result = list(drafts)
        for index, draft in enumerate(drafts):
            if draft.marker == "after" and index > 0:
                result[index - 1], result[index] = result[index], result[index - 1]
            elif draft.marker == "before" and index == 0 and len(drafts) > 1:
                result[0], result[1] = result[1], result[0]
        return result

    def set_arm(self, draft: Draft | None, arm: ArmPhrase) -> None:
        if draft is None:
            raise self.fail(arm.column, "this arm phrase belongs to no action")
        if draft.arm is not None and draft.arm != arm.side:
            raise self.fail(arm.column, f"two arms named for one action ({draft.arm} and "
                                        f"{arm.side})")
        draft.arm = arm.side

    def action(self, action: Action, current: Draft | None,
               focus: lf.Ref | None) -> tuple[Draft, list[Draft]]:
        """Apply an action clause; returns (the current draft, the drafts it started)."""
        meanings = self.meanings(action.chain, describing=action.verb in _PICK_VERBS)
        anaphoric = isinstance(action.obj, It) or action.obj.det == "that"
        referent = current.object if current is not None else focus
        if anaphoric and current is not None and current.shared:
            raise self.fail(action.obj.column, "'it' could be any of the objects named "
                                               "together before; name the object")
        if anaphoric and referent is None:
            word = "it" if isinstance(action.obj, It) else f"that {action.obj.head}"
            raise self.fail(action.obj.column, f"'{word}' does not refer to anything here")
        described, destination, toward, route = self.split_chain(action, meanings)
        if anaphoric:
            obj = self.resolve_anaphor(action.obj, referent, described)
        else:
            obj = self.describe(action.obj, described)
        if (anaphoric and action.marker == "after" and action.verb in _PICK_VERBS
                and current is not None and obj == current.object and not action.earlier):
            return current, []  # 'place X on Y after picking it up': the placement picks it
        objects = [self.conjunct(np, chain) for np, chain in action.earlier]
        # 'pick up X before placing it on Y' is one placement, like 'pick up X and place it'
        continues = (anaphoric and current is not None and current.kind == "hold"
                     and obj == current.object and toward is None
                     and action.marker in (None, "before") and not objects)
        started = []
        if not continues:
            started = [Draft(object=o, column=action.column, marker=action.marker,
                             shared=bool(objects)) for o in [*objects, obj]]
            current = started[-1]
        for draft in started or [current]:
            if destination is not None:
                draft.destination, draft.kind = destination, "place"
            if toward is not None:
                draft.toward, draft.kind = toward, "push"
            for waypoint_meaning in route:
                self.add_waypoint(draft, waypoint_meaning.relation, waypoint_meaning.landmark,
                                  waypoint_meaning.column)
            if action.lead_arm is not None:
                self.set_arm(draft, action.lead_arm)
        return current, started

    def conjunct(self, np: NP | It, chain: list[Link]) -> lf.Ref:
        """An object named before the last one in 'A and B': described by its own words."""
        if isinstance(np, It) or np.det == "that":
            raise self.fail(np.column, "name each object of 'A and B' in full")
        meanings = self.meanings(chain, describing=True)
        for m in meanings:
            if m.kind not in ("relation", "source", "extreme", "constraint", "noun"):
                raise self.fail(m.column, "say where to put the objects after the last one")
        return self.describe(np, meanings)

    def split_chain(self, action: Action, meanings: list[Meaning]):
        """Split a chain into (object modifiers, destination, push target, route links)."""
        route = [m for m in meanings if m.kind == "route"]
        links = [m for m in meanings if m.kind != "route"]
        for m in links:
            if m.kind == "particle" and action.verb not in _PARTICLES[m.relation]:
                raise self.fail(m.column, f"'{m.relation}' goes with "
                                          f"'{_PARTICLES[m.relation][0]}'")
        links = [m for m in links if m.kind != "particle"]
        pronoun = isinstance(action.obj, It)
        destination = toward = None
        if action.verb == "push":
            targets = [i for i, m in enumerate(links) if m.kind == "toward"] or [
                i for i, m in enumerate(links) if m.preposition == "to"]  # 'push X to Y'
            if len(targets) != 1:
                raise self.fail(action.column, "say which way to push: 'towards X' or "
                                               "'in the direction of X'")
            at = targets[0]
            toward = self.extend(links[at].landmark, [], links[at + 1:])
            links = links[:at]
        elif action.verb in _TRANSPORT_VERBS:
            kinds = _DESTINATION_KINDS.get(action.verb, ("relation", "destination"))
            candidates = [i for i, m in enumerate(links) if m.kind in kinds and not m.negated]
            if candidates:
                at = candidates[0] if pronoun else candidates[-1]
                chosen = links[at]
                if chosen.relation not in _PLACE_RELATIONS:
                    raise self.fail(chosen.column, "not supported: placing an object "
                                    + _UNPLACEABLE.get(chosen.relation, chosen.relation) +
                                    "; say 'on', 'in', 'next to', 'to the left of', 'to the "
                                    "right of', 'behind' or 'in front of' one object")
                landmark = self.extend(chosen.landmark, [], links[at + 1:])
                relation = chosen.relation
                if chosen.preposition == "to" and landmark.noun in _CONTAINERS:
                    relation = "in"  # 'move it to the bowl'
                destination = lf.Placement(relation=relation, landmark=landmark)
                links = links[:at]
            elif action.verb in _DESTINATION_REQUIRED:
                raise self.fail(action.column, "say where to put it (e.g. 'on the red cube', "
                                               "'behind the bowl')")
        for m in links:
            if m.kind in ("destination", "toward"):
                word = "a destination" if m.kind == "destination" else "a push direction"
                raise self.fail(m.column, f"{word} does not fit here")
        if pronoun and links:
            raise self.fail(links[0].column, "'it' cannot be described further; describe the "
                                             "object where it is first named")
        return links, destination, toward, route

    def resolve_anaphor(self, obj: NP | It, referent: lf.Ref, described: list[Meaning]) -> lf.Ref:
        if isinstance(obj, It):
            return referent
        if obj.premods or described:
            raise self.fail(obj.column, "'that <noun>' takes no further description")
        noun = self.narrower(referent.noun, self.head_noun(obj, None))
        if noun is None:
            raise self.fail(obj.column, f"'that {obj.head}' cannot be the {referent.noun} "
                                        "mentioned before")
        return referent.model_copy(update={"noun": noun})

    def add_waypoint(self, draft: Draft, mode: str, landmark: lf.Ref | It, column: int) -> None:
        if draft.kind == "push":
            raise self.fail(column, "a push has no route; routes constrain a carried object")
        if isinstance(landmark, It):
            if draft.last_landmark is None:
                raise self.fail(landmark.column, "'it' does not refer to a route landmark here")
            landmark = draft.last_landmark
        draft.route.append(lf.Waypoint(mode=mode, landmark=landmark))
        draft.last_landmark = landmark
        draft.route_column = draft.route_column or column

    def route(self, phrase: RoutePhrase, draft: Draft | None) -> None:
        if draft is None:
            raise self.fail(phrase.column, "a route needs an object: pick something up first")
        for negated, part in phrase.parts:
            if isinstance(part, PP):
                meaning = self.pp(part)
                if meaning.kind != "route":
                    raise self.fail(part.column, "a route goes 'over X' or 'around X'")
                mode, landmark = meaning.relation, meaning.landmark
            elif isinstance(part, (NP, It)):  # 'avoid X' names the landmark directly
                mode = "via"
                landmark = part if isinstance(part, It) else self.simple(part)
            else:
                raise self.fail(part.column, "a route goes 'over X' or 'around X'")
            if negated:
                if mode == "avoid":
                    raise self.fail(phrase.column, "a negated detour has no meaning here")
                mode = "avoid"
            self.add_waypoint(draft, mode, landmark, phrase.column)

    def orientation(self, phrase: OrientationPhrase, draft: Draft | None) -> None:
        if draft is None or draft.kind == "push":
            raise self.fail(phrase.column, "an orientation needs an object to place")
        value = lf.Orientation(side=phrase.side, facing=phrase.facing)
        if draft.orientation is not None and draft.orientation != value:
            raise self.fail(phrase.column, "two different orientations for one placement")
        draft.orientation, draft.orientation_column = value, phrase.column

    def command(self, draft: Draft, default_arm: str | None) -> lf.Pick | lf.Place | lf.Push:
        arm = draft.arm or default_arm
        if draft.kind == "push":
            return lf.Push(arm=arm, object=draft.object, toward=draft.toward)
        if draft.kind == "place":
            modes = {}
            for waypoint in draft.route:
                if modes.setdefault(waypoint.landmark, waypoint.mode) != waypoint.mode:
                    raise self.fail(draft.route_column, "the route both passes over and "
                                                        "avoids the same object")
            return lf.Place(arm=arm, object=draft.object, destination=draft.destination,
                            route=tuple(draft.route), orientation=draft.orientation)
        if draft.route:
            raise self.fail(draft.route_column, "a route needs a destination: say where to "
                                                "place the object")
        if draft.orientation is not None:
            raise self.fail(draft.orientation_column, "an orientation needs a destination: say "
                                                      "where to place the object")
        return lf.Pick(arm=arm, object=draft.object)

    # ---------------------------------------------------------------- referring expressions
    def narrower(self, a: str, b: str) -> str | None:
        """The more specific of two nouns, or None when they cannot name one object."""
        if a == b or b == "object" or _NOUN_PARENTS.get(a) == b:
            return a
        if a == "object" or _NOUN_PARENTS.get(b) == a:
            return b
        return None

    @staticmethod
    def head_noun(np: NP, domain: lf.Ref | None) -> str:
        if np.head == "one":
            return domain.noun if domain is not None else "object"
        return np.head

    def premod(self, premod) -> lf.Constraint:
        if premod.kind == "color":
            return lf.ColorIs(color=premod.value, negated=premod.negated)
        if premod.kind == "size":
            return lf.SizeIs(size=premod.value)
        if premod.kind == "extreme":
            return lf.ExtremeIs(extreme=premod.value, negated=premod.negated)
        if premod.kind == "middle":
            if premod.negated:
                raise self.fail(premod.column, "'non-middle' is not supported; say 'leftmost', "
                                               "'rightmost' or 'the second ... from the left'")
            return lf.MiddleIs()
        if premod.kind == "ordinal":
            return lf.OrdinalIs(rank=premod.rank, side=premod.value)
        return lf.NotKind(noun=premod.value)

    def describe(self, np: NP, meanings: list[Meaning]) -> lf.Ref:
        """A noun phrase plus the chain links that describe it."""
        if np.det == "that":
            raise self.fail(np.column, "'that <noun>' refers back to an object; none is "
                                       "mentioned before it")
        constraints = [self.premod(p) for p in np.premods]
        domain = self.domain
        if np.head == "one" and domain is not None:
            constraints.extend(domain.constraints)
        try:
            return self.extend(self.head_noun(np, domain), constraints, meanings)
        except ValueError as error:  # e.g. two ordinals for one object
            raise self.fail(np.column, _reason(error)) from None

    def simple(self, np: NP) -> lf.Ref:
        """A landmark: a noun phrase described by its own words only."""
        if np.det in ("that", "no"):
            raise self.fail(np.column, f"'{np.det}' cannot introduce a landmark")
        return self.describe(np, [])

    def extend(self, noun: str | lf.Ref, constraints: list, meanings: list[Meaning]) -> lf.Ref:
        """A reference from a noun (or an existing reference), constraints and chain links."""
        if isinstance(noun, lf.Ref):
            if not constraints and not meanings:
                return noun
            noun, constraints = noun.noun, list(noun.constraints) + constraints
        for m in meanings:
            if m.kind == "relation" and m.relation == "between":
                constraints.append(lf.Between(landmarks=m.landmark, negated=m.negated))
            elif m.kind in ("relation", "source"):
                constraints.append(lf.Related(relation=m.relation, landmark=m.landmark,
                                              negated=m.negated))
            elif m.kind == "extreme":
                constraints.append(lf.ExtremeIs(extreme=m.relation, negated=m.negated))
            elif m.kind == "constraint":
                constraints.append(m.constraint)
            elif m.kind == "noun":
                narrowed = self.narrower(noun, m.noun)
                if narrowed is None:
                    raise self.fail(m.column, f"a {noun} cannot be a {m.noun}")
                noun = narrowed
                constraints.extend(m.constraint)
            else:
                raise self.fail(m.column, "this phrase cannot describe an object")
        return lf.Ref(noun=noun, constraints=tuple(constraints))

    # ---------------------------------------------------------------- chain links
    def meanings(self, chain: list[Link], describing: bool = False) -> list[Meaning]:
        """The chain's links; `describing`: 'over X' describes (above X) rather than routes."""
        result = []
        for link in chain:
            if link.kind == "particle":
                result.append(Meaning("particle", link.column, link.value))
            elif link.kind == "pp":
                meaning = self.pp(link.value, describing)
                if link.negated and meaning.kind == "constraint" and hasattr(
                        meaning.constraint, "negated"):  # 'not closest to X'
                    meaning.constraint = meaning.constraint.model_copy(update={"negated": True})
                elif link.negated:
                    if meaning.kind not in ("relation", "extreme"):
                        raise self.fail(link.column, "only a relation or a position can be "
                                                     "negated here")
                    meaning.negated = True
                    meaning.column = link.column
                result.append(meaning)
            else:
                result.append(self.predicate(link.value, link.negated, link.column))
        return result

    def predicate(self, predicate, negated: bool, column: int) -> Meaning:
        """'(not) red', '(not) a cube', '(not) in the bowl', 'right of X' ... as one meaning."""
        if isinstance(predicate, Region):
            predicate = Predicate("pp", PP("at", predicate, predicate.column), predicate.column)
        kind, value = predicate.kind, predicate.value
        if kind == "pp":
            meaning = self.pp(value, describing=True)
            if meaning.kind == "source":
                meaning.kind = "relation"
                if value.preposition.startswith("off"):  # 'that is off the table'
                    negated = not negated
            if meaning.kind == "constraint":
                constraint = meaning.constraint
                if negated:
                    if not hasattr(constraint, "negated"):
                        raise self.fail(column, "'in the middle' cannot be negated")
                    constraint = constraint.model_copy(update={"negated": True})
                return Meaning("constraint", column, constraint=constraint)
            if meaning.kind not in ("relation", "extreme"):
                raise self.fail(value.column, "this phrase cannot describe an object")
            meaning.negated = negated
            return Meaning("constraint", column, constraint=self.extend(
                "object", [], [meaning]).constraints[0])
        elif kind == "color":
            constraint = lf.ColorIs(color=value, negated=negated)
        elif kind == "ordinal":
            if negated:
                raise self.fail(column, "'not the second ...' is not supported; describe the "
                                        "object by what it is")
            constraint = self.premod(value)
            if predicate.noun not in (None, "one"):
                return Meaning("noun", column, noun=predicate.noun, constraint=[constraint])
        elif kind == "extreme":
            constraint = lf.ExtremeIs(extreme=value, negated=negated)
            if predicate.noun not in (None, "one"):  # 'not the rightmost ball'
                return Meaning("noun", column, noun=predicate.noun, constraint=[constraint])
        elif kind == "size":
            if negated:
                raise self.fail(column, "say 'larger' or 'smaller' instead of negating a size")
            constraint = lf.SizeIs(size=value)
            if predicate.noun not in (None, "one"):  # 'the larger cylinder'
                return Meaning("noun", column, noun=predicate.noun, constraint=[constraint])
        elif kind == "kind":
            if negated:
                if value.premods:
                    raise self.fail(column, "only a bare noun can be negated: 'not a cube'")
                constraint = lf.NotKind(noun=value.head)
            else:
                return Meaning("noun", column, noun=value.head,
                               constraint=[self.premod(p) for p in value.premods])
        else:
            raise self.fail(column, "'empty' describes a container in a condition")
        return Meaning("constraint", column, constraint=constraint)

    def pp(self, pp: PP, describing: bool = False) -> Meaning:
        """One prepositional phrase; `describing`: 'over X' means above X, not a route."""
        preposition, target = pp.preposition, pp.target
        if preposition == "between":
            landmarks = (self.simple(target), self.simple(pp.second))
            if landmarks[0] == landmarks[1]:
                raise self.fail(pp.second.column, "'between' needs two different objects")
            return Meaning("relation", pp.column, "between", landmarks)
        if preposition in ("nearest", "farthest"):
            return Meaning("constraint", pp.column, constraint=lf.NearestIs(
                nearness=preposition, landmark=self.simple(target)))
        if describing and preposition == "over" and isinstance(target, NP):
            return Meaning("relation", pp.column, "above", self.simple(target))
        if isinstance(target, It):
            if _NP_PREPOSITIONS.get(preposition, ("",))[0] != "route":
                raise self.fail(target.column, "'it' can only name a route landmark here")
            return Meaning("route", pp.column, _NP_PREPOSITIONS[preposition][1], target)
        if isinstance(target, NP):
            if preposition not in _NP_PREPOSITIONS:
                raise self.fail(pp.column, f"'{preposition.replace('_', ' ')}' needs a "
                                           "relation, e.g. 'at the position right of X'")
            kind, relation = _NP_PREPOSITIONS[preposition]
            landmark = self.simple(target)
            if kind == "source" and relation is None:
                relation = "in" if landmark.noun in _CONTAINERS else "on"
            return Meaning(kind, pp.column, relation, landmark, preposition=preposition)
        kind = _REGION_PREPOSITIONS.get((target.kind, preposition))
        if kind is None:
            raise self.fail(pp.column, f"'{preposition.replace('_', ' ')}' does not combine "
                                       f"with this phrase")
        if kind == "middle":
            return Meaning("constraint", pp.column, constraint=lf.MiddleIs())
        if kind == "position":
            inner = target.inner
            meaning = self.pp(inner) if isinstance(inner, PP) else self.pp(
                PP("to", inner, inner.column))
            if meaning.kind != "relation":
                raise self.fail(pp.column, "'the position' must be next to something, e.g. "
                                           "'the position right of the blue sphere'")
            meaning.column = pp.column
            return meaning
        if kind == "extreme":
            extreme = (target.value if target.kind == "extreme_position"
                       else _SIDE_EXTREMES[target.value])
            return Meaning("extreme", pp.column, extreme)
        landmark = self.simple(target.np)
        relation = {"side_of": _SIDE_RELATIONS.get(target.value), "front_of": "in_front_of",
                    "back_of": "behind", "top_of": "on"}.get(target.kind)
        if kind == "source":
            relation = "on"
        return Meaning(kind, pp.column, relation, landmark)


def _reason(error: ValueError) -> str:
    """What a failed check of a logical form says (pydantic's first error, unwrapped)."""
    if isinstance(error, ValidationError):
        first = error.errors(include_url=False)[0]
        cause = first.get("ctx", {}).get("error")
        return str(cause) if cause is not None else first["msg"]
    return str(error)
