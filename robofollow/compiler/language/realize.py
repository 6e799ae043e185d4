"""Logical form -> English, in several paraphrase styles.

Every style is a complete way of speaking: `parse(realize(lf, style)) == lf` for every LF and
style (a property the tests check). The structure is decided here, following the parser's
attachment rules (semantics.py): a destination landmark is described with relative clauses
("behind the block that is left of the ball"), never with bare phrases that the parser would
take as the destination; landmarks of relations use only premodifiers ("the non-leftmost
ball"). The words and frames live in templates/english.j2.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from functools import cache, wraps
from typing import TYPE_CHECKING

from robofollow.compiler.language import lf

if TYPE_CHECKING:
    import jinja2


@dataclass(frozen=True)
class Style:
    name: str
    arm: str  # lead ("use your left arm to"), trailing ("... using your left arm"), fronted
    arm_word: str  # trailing arm: "using" / "with"
    pick_verb: str
    pick_gerund: str
    place_form: str  # "it" (pick up X and place it D) or "direct" (put X D)
    place_verb: str
    place_joiner: str
    direct_verb: str
    direct_gerund: str
    push_preposition: str
    via: str  # pass, move, go
    avoid: str  # avoid, detour, around, while
    orientation: str  # with, bare, its
    sequence: str  # first, start, before, after
    conditional: str  # if, when, check, unless
    condition: str  # there_is, possessive, state
    extreme: str  # premod (leftmost cube), left (left cube), post (cube on the left), relative
    negation: str  # relative ("that is not red"), pp ("not in the bowl"), non ("non-red")
    relation: str  # pp ("to the left of X") or relative ("that is to the left of X")
    sides: str  # "to the {} of" / "on the {} side of"
    destinations: dict[str, str] = field(default_factory=dict)
    nouns: dict[str, str] = field(default_factory=dict)
    among: bool = False


_SIDE_DESTINATIONS = {"in_front_of": "in front of", "behind": "behind"}

STYLES: dict[str, Style] = {style.name: style for style in (
    Style("plain", arm="lead", arm_word="using", pick_verb="pick up", pick_gerund="picking up",
          place_form="it", place_verb="place", place_joiner="and", direct_verb="put",
          direct_gerund="putting", push_preposition="towards", via="pass", avoid="avoid",
          orientation="with", sequence="first", conditional="if", condition="there_is",
          extreme="premod", negation="relative", relation="pp", sides="to the {} of",
          destinations={"on": "on", "in": "in", "next_to": "next to"}),
    Style("trailing", arm="trailing", arm_word="using", pick_verb="grasp",
          pick_gerund="grasping", place_form="direct", place_verb="put", place_joiner="and",
          direct_verb="move", direct_gerund="moving", push_preposition="in the direction of",
          via="move", avoid="while", orientation="bare", sequence="before", conditional="when",
          condition="possessive", extreme="post", negation="pp", relation="pp",
          sides="on the {} side of",
          destinations={"on": "onto", "in": "into", "next_to": "beside"},
          nouns={"sphere": "ball"}),
    Style("fronted", arm="fronted", arm_word="using", pick_verb="take", pick_gerund="taking",
          place_form="it", place_verb="put", place_joiner="then", direct_verb="place",
          direct_gerund="placing", push_preposition="toward", via="go", avoid="detour",
          orientation="its", sequence="start", conditional="check", condition="state",
          extreme="relative", negation="relative", relation="relative", sides="to the {} of",
          destinations={"on": "on top of", "in": "inside", "next_to": "next to",
                        "left_of": "at the position left of",
                        "right_of": "at the position right of"},
          nouns={"object": "item", "slab": "bar"}),
    Style("varied", arm="trailing", arm_word="with", pick_verb="grab", pick_gerund="grabbing",
          place_form="it", place_verb="set", place_joiner="and then", direct_verb="put",
          direct_gerund="putting", push_preposition="toward", via="move", avoid="around",
          orientation="with", sequence="after", conditional="unless", condition="possessive",
          extreme="left", negation="non", relation="relative", sides="on the {} side of",
          destinations={"on": "on", "in": "into", "next_to": "beside"},
          nouns={"sphere": "ball", "label": "square label"}, among=True),
)}

_PLURALS = {"sphere": "spheres", "ball": "balls", "object": "objects", "item": "items",
            "block": "blocks", "cube": "cubes", "cylinder": "cylinders", "slab": "slabs",
            "bar": "bars", "bowl": "bowls", "label": "labels", "square label": "labels",
            "table": "tables"}
_SIDE_WORDS = {"leftmost": "left", "rightmost": "right", "frontmost": "front",
               "backmost": "back"}
_EXTREME_POSITIONS = {"leftmost": "on the left", "rightmost": "on the right",
                      "frontmost": "in the frontmost position",
                      "backmost": "in the backmost position"}
_RELATION_WORDS = {"in_front_of": "in front of", "behind": "behind", "on": "on", "in": "in",
                   "next_to": "next to", "touching": "touching", "above": "above",
                   "below": "below"}
_ORDINAL_WORDS = {1: "first", 2: "second", 3: "third", 4: "fourth", 5: "fifth"}
_NEARNESS_WORDS = {"nearest": "closest to", "farthest": "farthest from"}


_PREMODIFIERS = (lf.ColorIs, lf.SizeIs, lf.ExtremeIs, lf.MiddleIs, lf.NotKind, lf.OrdinalIs)


def _english_order(c: lf.Constraint) -> int:
    """Premodifiers in English order: superlative or 'middle', then size, then colour or kind
    ('the rightmost smaller red cube'), so that the natural reading is the scored one."""
    if isinstance(c, (lf.ExtremeIs, lf.MiddleIs)):
        return 0
    return 1 if isinstance(c, lf.SizeIs) else 2


def _premodified(ref: lf.Ref) -> bool:
    """Whether every constraint of a reference is said before its noun (`Realizer.landmark`)."""
    return all(isinstance(c, _PREMODIFIERS) for c in ref.constraints)


@cache
def _frames() -> jinja2.runtime.TemplateModule:
    """The English templates (jinja2 is imported here: `robofollow parse --help` and the
    commands that never speak need not load it)."""
    import jinja2

    env = jinja2.Environment(
        loader=jinja2.PackageLoader("robofollow.compiler.language", "templates"),
        autoescape=False, undefined=jinja2.StrictUndefined)
    return env.get_template("english.j2").module


def _article(phrase: str) -> str:
    return ("an " if phrase[:1] in "aeiou" else "a ") + phrase


def _sentence(text: str) -> str:
    text = re.sub(r"\s+", " ", text).strip()
    text = re.sub(r"(^|[.] )([a-z])", lambda m: m.group(1) + m.group(2).upper(), text)
    return text + "."


def _by_node(method):
    """Memoise a Realizer method on its node's identity and its other arguments, for the
    realizer's life (the split generator speaks thousands of forms that share their parts;
    the entry keeps its node alive, so an id is never reused while cached)."""
    @wraps(method)
    def said(self, node, *args, **options):
        key = method.__name__, id(node), args, tuple(options.items())
        hit = self._said.get(key)
        if hit is None or hit[0] is not node:
            hit = self._said[key] = node, method(self, node, *args, **options)
        return hit[1]
    return said


class Realizer:
    """Speaks logical forms in one style (one realizer may speak many forms)."""

    def __init__(self, style: Style):
        self.s = style
        self.t = _frames()
        self._said: dict[tuple, tuple[object, str]] = {}

    # ---------------------------------------------------------------- instructions
    def instruction(self, instruction: lf.Instruction) -> str:
        if isinstance(instruction, lf.Conditional):
            return _sentence(self.conditional(instruction))
        return _sentence(self.body(instruction, top=True))

    def conditional(self, c: lf.Conditional) -> str:
        form = self.s.conditional
        condition = c.condition
        if form == "unless":
            positive = self.positive(condition)
            form, condition = ("unless", positive) if positive is not None else ("if", condition)
        if form == "check" and c.otherwise is None:
            form = "if"
        otherwise = self.body(c.otherwise) if c.otherwise is not None else None
        return str(self.t.conditional(form, self.condition(condition), self.body(c.then),
                                      otherwise))

    @staticmethod
    def positive(condition: lf.Condition) -> lf.Condition | None:
        """The condition with its negation removed, when it is negated ('unless' form)."""
        if isinstance(condition, lf.Exists):
            return condition.model_copy(update={"negated": False}) if condition.negated else None
        prop = condition.property
        if getattr(prop, "negated", False):
            return lf.Holds(subject=condition.subject,
                            property=prop.model_copy(update={"negated": False}))
        return None

    @_by_node
    def body(self, body: lf.Body, top: bool = False) -> str:
        if not isinstance(body, lf.Sequence):
            among = self.among(body) if top else None
            return among if among is not None else self.command(body, self.s.arm)
        form = self.s.sequence
        if form in ("before", "after") and len(body.steps) != 2:
            form = "then"
        # an arm phrase in front of a sequence would name the arm of every step
        arm_mode = "lead" if self.s.arm == "fronted" else self.s.arm
        steps = [self.command(step, arm_mode) for step in body.steps]
        gerunds = [self.command(step, "trailing", gerund=True) for step in body.steps]
        return str(self.t.sequence(form, steps, gerunds))

    # ---------------------------------------------------------------- commands
    @_by_node
    def command(self, c: lf.Pick | lf.Place | lf.Push, arm_mode: str, obj: str | None = None,
                gerund: bool = False) -> str:
        """One command; `arm_mode` is lead, trailing or fronted; `gerund` for 'before X-ing'."""
        obj = obj if obj is not None else self.ref(c.object)
        tail: list[str] = []
        if isinstance(c, lf.Pick):
            clause = str(self.t.pick(self.s, obj, gerund))
        elif isinstance(c, lf.Push):
            clause = str(self.t.push(self.s, obj, self.ref(c.toward), gerund))
        else:
            clause, tail = self.place(c, obj, gerund)
        if c.arm is not None:
            if arm_mode == "lead":
                clause = f"{self.t.arm_lead(c.arm)} {clause}"
            elif arm_mode == "fronted":
                clause = f"{self.t.arm_fronted(c.arm)} {clause}"
            else:
                clause = f"{clause} {self.t.arm_trailing(self.s, c.arm)}"
        return clause + "".join(tail)

    def place(self, c: lf.Place, obj: str, gerund: bool) -> tuple[str, list[str]]:
        """The placement clause and what follows the arm phrase (routes, orientation)."""
        destination = self.destination(c.destination)
        vias = [w for w in c.route if w.mode == "via"]
        avoids = [w for w in c.route if w.mode == "avoid"]
        tail: list[str] = []
        if self.s.place_form == "it" and not gerund:
            clauses = [str(self.t.via(self.s, self.landmark(w.landmark))) for w in vias]
            clauses += [str(self.t.avoid(self.s, self.landmark(w.landmark))) for w in avoids]
            clause = str(self.t.place_with_it(self.s, obj, clauses, destination))
        else:
            clause = str(self.t.place_direct(self.s, obj, [self.landmark(w.landmark) for w in vias],
                                             destination, gerund=gerund))
            tail += [", " + str(self.t.avoid(self.s, self.landmark(w.landmark)))
                     for w in avoids]
        if c.orientation is not None:
            words = str(self.t.orientation(self.s, c.orientation.side, c.orientation.facing))
            tail.append(words if words.startswith(",") else " " + words)
        return clause, tail

    def among(self, c: lf.Pick | lf.Place | lf.Push) -> str | None:
        """'Among the cubes, pick up the one on the left' when the object allows it."""
        if not self.s.among or c.object.noun == "object":
            return None
        extremes = [x for x in c.object.constraints
                    if isinstance(x, lf.ExtremeIs) and not x.negated]
        others = [x for x in c.object.constraints if x not in extremes]
        if len(extremes) != 1 or not all(isinstance(x, (lf.ColorIs, lf.SizeIs)) and
                                         not getattr(x, "negated", False) for x in others):
            return None
        domain = " ".join([self.premod(x) for x in sorted(others, key=_english_order)] +
                          [_PLURALS[self.noun(c.object.noun)]])
        obj = f"the one {_EXTREME_POSITIONS[extremes[0].extreme]}"
        arm_mode = "lead" if self.s.arm == "fronted" else self.s.arm
        return f"among the {domain}, {self.command(c, arm_mode, obj=obj)}"

    # ---------------------------------------------------------------- conditions
    @_by_node
    def condition(self, c: lf.Condition) -> str:
        if isinstance(c, lf.Holds):
            negated = isinstance(c.property, lf.NotKind) or getattr(c.property, "negated", False)
            return str(self.t.holds(self.ref(c.subject), self.predicate(c.property), negated))
        relations = [x for x in c.ref.constraints if isinstance(x, lf.Related)]
        if (len(relations) == 1 and not relations[0].negated
                and relations[0].relation in ("in", "on") and _premodified(relations[0].landmark)):
            container = self.landmark(relations[0].landmark)
            rest = lf.Ref(noun=c.ref.noun,
                          constraints=tuple(x for x in c.ref.constraints if x != relations[0]))
            if self.s.condition == "state" and relations[0].relation == "in" and rest == lf.Ref(
                    noun="object"):
                return str(self.t.emptiness(container, c.negated))
            if self.s.condition == "possessive" and _premodified(rest):
                thing = _article(self.landmark(rest, determiner=False))
                frame = self.t.contains if relations[0].relation == "in" else self.t.has_on_top
                return str(frame(container, thing, c.negated))
        thing = self.ref(c.ref, determiner=False)
        return str(self.t.there_is(thing if c.negated else _article(thing), c.negated))

    def predicate(self, p: lf.Constraint) -> str:
        if isinstance(p, lf.ColorIs):
            return p.color
        if isinstance(p, lf.SizeIs):
            return p.size
        if isinstance(p, lf.ExtremeIs):
            return p.extreme
        if isinstance(p, lf.NotKind):
            return _article(self.noun(p.noun))
        if isinstance(p, lf.OrdinalIs):
            return f"the {_ORDINAL_WORDS[p.rank]} {self.from_side(p)}"
        if isinstance(p, lf.MiddleIs):
            return "in the middle"
        if isinstance(p, lf.NearestIs):
            return f"the {self.nearness_phrase(p)}"
        if isinstance(p, lf.Between):
            return self.between_phrase(p)
        return self.relation_phrase(p.relation, p.landmark)

    # ---------------------------------------------------------------- referring expressions
    def noun(self, noun: str) -> str:
        return self.s.nouns.get(noun, noun)

    def relation_phrase(self, relation: str, landmark: lf.Ref) -> str:
        if relation in ("left_of", "right_of"):
            words = self.s.sides.format(relation.removesuffix("_of"))
        else:
            words = _RELATION_WORDS[relation]
        return f"{words} {self.landmark(landmark)}"

    def between_phrase(self, c: lf.Between) -> str:
        first, second = (self.landmark(landmark) for landmark in c.landmarks)
        return f"between {first} and {second}"

    def nearness_phrase(self, c: lf.NearestIs) -> str:
        return f"{_NEARNESS_WORDS[c.nearness]} {self.landmark(c.landmark)}"

    @staticmethod
    def from_side(c: lf.OrdinalIs) -> str:
        return f"from the {c.side}"

    def destination(self, d: lf.Placement) -> str:
        words = self.s.destinations.get(d.relation)
        if words is None:
            words = (_SIDE_DESTINATIONS.get(d.relation) or
                     self.s.sides.format(d.relation.removesuffix("_of")))
        return f"{words} {self.ref(d.landmark, relative=True)}"

    def premod(self, c: lf.Constraint) -> str:
        """A constraint as a word before the noun ('red', 'non-leftmost', 'non-cube')."""
        if isinstance(c, lf.ColorIs):
            return ("non-" if c.negated else "") + c.color
        if isinstance(c, lf.SizeIs):
            return c.size
        if isinstance(c, lf.ExtremeIs):
            if c.negated:
                return "non-" + c.extreme
            return _SIDE_WORDS[c.extreme] if self.s.extreme == "left" else c.extreme
        if isinstance(c, lf.MiddleIs):
            return "middle"
        return "non-" + c.noun

    def head(self, ref: lf.Ref, premods: list[str]) -> list[str]:
        """Premodifiers and noun, inside an ordinal's frame ('second ... cube from the left')
        when the reference has one."""
        ordinal = next((c for c in ref.constraints if isinstance(c, lf.OrdinalIs)), None)
        words = premods + [self.noun(ref.noun)]
        if ordinal is None:
            return words
        return [_ORDINAL_WORDS[ordinal.rank], *words, self.from_side(ordinal)]

    @_by_node
    def landmark(self, ref: lf.Ref, determiner: bool = True) -> str:
        """A reference described by premodifiers only."""
        premods = [self.premod(c) for c in sorted(ref.constraints, key=_english_order)
                   if not isinstance(c, lf.OrdinalIs)]
        return ("the " if determiner else "") + " ".join(self.head(ref, premods))

    @_by_node
    def ref(self, ref: lf.Ref, determiner: bool = True, relative: bool = False) -> str:
        """A reference; `relative` puts every relation in a relative clause."""
        premods: list[str] = []
        posts: list[tuple[str, str]] = []  # (how it opens when first: "", "that is", ..., phrase)
        for c in sorted(ref.constraints, key=_english_order):
            if isinstance(c, lf.OrdinalIs):
                continue
            post = self.postmodifier(c, relative)
            if post is None:
                premods.append(self.premod(c))
            else:
                posts.append(post)
        words = self.head(ref, premods)
        if posts:
            (opening, first), rest = posts[0], [phrase for _, phrase in posts[1:]]
            words.append(" and ".join([f"{opening} {first}".strip()] + rest))
        return ("the " if determiner else "") + " ".join(words)

    def postmodifier(self, c: lf.Constraint, relative: bool) -> tuple[str, str] | None:
        """A constraint said after the noun, or None when the style says it before."""
        negated = getattr(c, "negated", False) or isinstance(c, lf.NotKind)
        if isinstance(c, (lf.Related, lf.Between, lf.NearestIs)):
            # 'above X' after a transport verb would be a route: always a relative clause
            as_pp = not relative and getattr(c, "relation", "") != "above" and (
                self.s.negation == "pp" if negated else self.s.relation == "pp")
            if isinstance(c, lf.Related):
                phrase = self.relation_phrase(c.relation, c.landmark)
            elif isinstance(c, lf.Between):
                phrase = self.between_phrase(c)
            elif as_pp:
                phrase = self.nearness_phrase(c)
            elif negated:
                phrase = f"the {self.nearness_phrase(c)}"
            else:  # 'the' only with the opening: after 'and', 'the closest ...' would be a noun
                return ("that is the", self.nearness_phrase(c))  # phrase, not a description
            return ("" if as_pp else "that is", ("not " if negated else "") + phrase)
        if isinstance(c, lf.ExtremeIs) and not negated and self.s.extreme in ("post", "relative"):
            if self.s.extreme == "post" and not relative:
                return ("", _EXTREME_POSITIONS[c.extreme])
            return ("that is", c.extreme)
        if negated and self.s.negation != "non":
            word = c.extreme if isinstance(c, lf.ExtremeIs) else self.predicate(c)
            return ("that is", "not " + word)
        return None

def realize(instruction: lf.Instruction, style: str = "plain") -> str:
    """English for a logical form, in one of STYLES."""
    return Realizer(STYLES[style]).instruction(instruction)
