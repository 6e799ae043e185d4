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

from dataclasses import dataclass, field

from robofollow.compiler.language import lf
from robofollow.compiler.language.references import (
    CONTAINERS,
    Meaning,
    ReferringExpressions,
)
from robofollow.compiler.language.syntax import (
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
    RoutePhrase,
    Steps,
)

_TRANSPORT_VERBS = frozenset({"place", "stack", "move", "take", "remove"})
_PICK_VERBS = frozenset({"pick", "grasp"})
# 'take X on Y' names where X is; 'take X onto / to Y' where it goes
_DESTINATION_KINDS = {"take": ("destination",)}
_DESTINATION_REQUIRED = frozenset({"place", "stack"})
_PLACE_RELATIONS = frozenset(lf.PlaceRelation.__args__)
_PARTICLES = {"up": ("pick", "grasp"), "down": ("place",)}  # particle -> verbs it goes with
_UNPLACEABLE = {"between": "between two objects", "above": "above an object (say 'on')",
                "below": "under an object", "touching": "touching an object"}

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


class Semantics(ReferringExpressions):
    """One instruction's semantic pass: steps, actions, destinations, routes, orientations and
    conditions; its referring expressions are ReferringExpressions' (references.py)."""

    # ---------------------------------------------------------------- entry
    def instruction(self, syntax) -> lf.Instruction:
        self.read_nouns(syntax)
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
                if chosen.preposition == "to" and landmark.noun in CONTAINERS:
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
