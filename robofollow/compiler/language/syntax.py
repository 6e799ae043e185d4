"""Parse-tree rules -> small syntax records (applied inline while the LALR parser reduces).

The records keep words, structure and columns; meaning is decided in semantics.py.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from lark import Transformer

from robofollow.compiler.language.lexicon import WordToken

# ---------------------------------------------------------------- records


@dataclass(slots=True)
class Premod:
    kind: str  # color, size, extreme, middle, ordinal, kind
    value: str  # for an ordinal: the side it counts from
    negated: bool
    column: int
    rank: int = 0  # for an ordinal

@dataclass(slots=True)
class Head:
    noun: str  # a noun, or "one"
    column: int


@dataclass(slots=True)
class NP:
    det: str | None
    premods: list[Premod]
    head: str  # a noun, or "one"
    column: int


@dataclass(slots=True)
class It:
    column: int


@dataclass(slots=True)
class Region:
    """A target that is not a plain noun phrase: 'the left side of X', 'top of X', ..."""

    kind: str  # side, side_of, extreme_position, middle, top_of, front_of, back_of,
    # direction_of, position
    value: str | None  # left/right or an extreme
    np: NP | None
    inner: PP | Region | None  # for 'the position <pp>'
    column: int


@dataclass(slots=True)
class PP:
    preposition: str  # a preposition, or between, nearest, farthest
    target: NP | It | Region
    column: int
    second: NP | None = None  # between's second landmark


@dataclass(slots=True)
class Predicate:
    """What follows 'that is' / 'is' / 'and': a pp, a bare region, a colour, ... ."""

    kind: str  # pp, region, color, size, extreme, kind, empty
    value: object
    column: int
    noun: str | None = None  # 'the rightmost ball': the noun said with an extreme


@dataclass(slots=True)
class Link:
    """One element of a modifier chain."""

    kind: str  # pp, predicate, particle
    value: PP | Predicate | str  # a particle's word
    negated: bool
    column: int


@dataclass(slots=True)
class Action:
    verb: str
    obj: NP | It
    chain: list[Link]
    gerund: bool
    column: int
    lead_arm: ArmPhrase | None = None
    marker: str | None = None  # before, after, start
    # 'pick up A and B': the objects named before the last one, each with its own chain
    earlier: list[tuple[NP | It, list[Link]]] = field(default_factory=list)


@dataclass(slots=True)
class ArmPhrase:
    side: str
    column: int


@dataclass(slots=True)
class RoutePhrase:
    parts: list[tuple[bool, PP | It | NP]]  # (negated, what follows the route verb)
    column: int


@dataclass(slots=True)
class OrientationPhrase:
    side: str
    facing: str
    column: int


@dataclass(slots=True)
class Among:
    premods: list[Premod]
    noun: str
    column: int


@dataclass(slots=True)
class Break:
    """A connective that starts a new sentence or a 'then' clause."""

    column: int


@dataclass(slots=True)
class Steps:
    segments: list
    column: int


@dataclass(slots=True)
class ConditionPhrase:
    kind: str  # there_is, is, contains, has_on_top
    subject: NP
    chain: list[Link]
    negated: bool
    predicate: Predicate | NP | None
    column: int


@dataclass(slots=True)
class ConditionalPhrase:
    condition: ConditionPhrase
    then: Steps
    otherwise: Steps | None
    negate_condition: bool
    column: int


# ---------------------------------------------------------------- helpers

_PREMOD_KINDS = {"COLOR": "color", "SIZE": "size", "EXTREME": "extreme", "MIDDLE": "middle",
                 "NOUN": "kind", "LABEL": "kind"}
_SIDE_EXTREMES = {"left": "leftmost", "right": "rightmost", "front": "frontmost",
                  "back": "backmost"}
_DETERMINERS = frozenset({"THE", "A", "THAT", "NO"})
_BREAKS = frozenset({"THEN", "PERIOD", "SEMICOLON"})
_PREPOSITION_NAMES = {"NEXT": "next_to", "OUT": "out_of"}


def column_of(item) -> int:
    """1-based column of a token or a record."""
    return item.column


def _has(children, terminal: str) -> bool:
    return any(isinstance(c, WordToken) and c.type == terminal for c in children)


def _first(children, kind):
    return next((c for c in children if isinstance(c, kind)), None)


def _side(children) -> str | None:
    return next((c.value for c in children
                 if isinstance(c, WordToken) and c.type in ("LEFT", "RIGHT")), None)


def _premod(item, negated: bool = False) -> Premod:
    """A premodifier token (or an already built 'non-' premodifier) as a record."""
    if isinstance(item, Premod):
        return item
    if item.type in _PREMOD_KINDS:
        return Premod(_PREMOD_KINDS[item.type], item.value, negated, item.column)
    return Premod("extreme", _SIDE_EXTREMES[item.value], negated, item.column)


def _premods(items) -> list[Premod]:
    return [_premod(item) for item in items]


class ToSyntax(Transformer):
    """Callbacks named after grammar rules and aliases (rules marked '?' in the grammar pass
    their only child through without a callback)."""

    def start(self, children):  # courtesy words carry no meaning
        return next(c for c in reversed(children) if not isinstance(c, WordToken))

    # ---- conditionals
    def if_(self, children):
        condition = _first(children, ConditionPhrase)
        then, *otherwise = [c for c in children if isinstance(c, Steps)]
        return ConditionalPhrase(condition, then, otherwise[0] if otherwise else None, False,
                                 children[0].column)

    def unless(self, children):
        conditional = self.if_(children)
        conditional.negate_condition = True
        return conditional

    def otherwise(self, children):
        return _first(children, Steps)

    def there_is(self, children):
        np = _first(children, NP)
        chain = _first(children, list) or []
        return ConditionPhrase("there_is", np, chain, np.det == "no", None, children[0].column)

    def is_(self, children):
        return ConditionPhrase("is", children[0], _first(children, list) or [],
                               _has(children, "NOT"), children[-1], children[0].column)

    def _possession(self, kind, children):
        subject, obj = [c for c in children if isinstance(c, NP)]
        negated = _has(children, "NOT") or obj.det == "no"
        return ConditionPhrase(kind, subject, _first(children, list) or [], negated, obj,
                               subject.column)

    def contains(self, children):
        return self._possession("contains", children)

    def has_on_top(self, children):
        return self._possession("has_on_top", children)

    def empty(self, children):
        return Predicate("empty", _has(children, "NON"), children[0].column)

    # ---- clauses
    def steps(self, children):
        segments: list = []
        for child in children:
            if not isinstance(child, WordToken):
                segments.append(child)
            elif child.type in _BREAKS and segments and not isinstance(segments[-1], Break):
                segments.append(Break(child.column))
        return Steps(segments, column_of(segments[0]))

    def arm_lead(self, children):
        arm, action = children[0], children[-1]
        action.lead_arm = arm
        return action

    def _marked(self, marker, children):
        action = children[-1]
        action.marker = marker
        action.column = children[0].column
        return action

    def start_by(self, children):
        return self._marked("start", children)

    def before(self, children):
        return self._marked("before", children)

    def after(self, children):
        return self._marked("after", children)

    def among(self, children):
        words = [c for c in children[1:-1] if getattr(c, "type", None) != "THE"]
        return Among(_premods(words), children[-1].value, children[0].column)

    def action(self, children, gerund=False):
        verb, conjuncts = children[0], []
        for child in children[1:]:
            if isinstance(child, list):
                conjuncts[-1] = (conjuncts[-1][0], child)
            elif not isinstance(child, WordToken):  # an object ('and' is a token)
                conjuncts.append((child, []))
        (obj, chain), earlier = conjuncts[-1], conjuncts[:-1]
        return Action(verb.value, obj, chain, gerund, verb.column, earlier=earlier)

    def gerund_action(self, children):
        return self.action(children, gerund=True)

    def verb(self, children):  # "pick up": the particle adds nothing
        return children[0]

    gerund = verb

    def arm(self, children):
        return ArmPhrase(_side(children), children[0].column)

    def route(self, children, negated=False):
        parts = [c for c in children if not isinstance(c, WordToken)]
        marks = [negated] + [True] * (len(parts) - 1)  # "go around X instead of passing over it"
        return RoutePhrase(list(zip(marks, parts, strict=True)), children[0].column)

    def avoid_route(self, children):
        return self.route(children, negated=True)

    def orientation(self, children):
        length = next(t for t in children if isinstance(t, WordToken) and t.type == "LENGTH")
        return OrientationPhrase(length.value, children[-1].value, children[0].column)

    # ---- referring expressions
    def np(self, children):
        det = children[0].value if getattr(children[0], "type", None) in _DETERMINERS else None
        premods = _premods(children[1 if det else 0:-1])
        return NP(det, premods, children[-1].value, column_of(children[0]))

    def ordinal_np(self, children):
        """'the second (red) cube from the left'; without a noun, 'one'."""
        det = children[0].value if children[0].type in _DETERMINERS else None
        ordinal = children[1 if det else 0]
        rank = 1 if ordinal.type == "FIRST" else int(ordinal.value)
        until = next(i for i, c in enumerate(children) if getattr(c, "type", None) == "FROM")
        words = children[children.index(ordinal) + 1:until]
        head = "one"
        if words and isinstance(words[-1], WordToken) and words[-1].type in (
                "NOUN", "ONE", "LABEL"):
            head = words.pop().value
        side = Premod("ordinal", children[-1].value, False, ordinal.column, rank)
        return NP(det, [side, *_premods(words)], head, children[0].column)

    def square_label(self, children):
        return children[-1]

    def non(self, children):
        premod = _premod(children[1], negated=True)
        premod.column = children[0].column
        return premod

    def chain(self, children):
        return children

    def link(self, children):
        return Link("pp", children[-1], _has(children, "NOT"), children[0].column)

    def relative(self, children):
        return Link("predicate", children[-1], _has(children, "NOT"), children[0].column)

    conjoined = relative

    def particle(self, children):
        return Link("particle", children[0].value, False, children[0].column)

    def predicate(self, children):
        return Predicate("pp", children[0], children[0].column)

    def colour(self, children):
        return Predicate("color", children[0].value, children[0].column)

    def size(self, children):  # 'larger', 'the larger (one)'
        size = next(c for c in children if c.type == "SIZE")
        noun = children[-1].value if children[-1] is not size else None
        return Predicate("size", size.value, children[0].column, noun)

    def extreme(self, children):  # 'leftmost', 'the leftmost (ball)'
        extreme = next(c for c in children if c.type == "EXTREME")
        noun = children[-1].value if children[-1] is not extreme else None
        return Predicate("extreme", extreme.value, children[0].column, noun)

    def ordinal(self, children):  # 'is the second (cube) from the left'
        np = self.ordinal_np(children)
        return Predicate("ordinal", np.premods[0], children[0].column, np.head)

    def the_superlative(self, children):
        return Predicate("pp", children[-1], children[0].column)

    def kind(self, children):
        np = NP(None, _premods(children[1:-1]), children[-1].value, children[0].column)
        return Predicate("kind", np, children[0].column)

    def pp(self, children):
        if len(children) == 1:  # a superlative
            return children[0]
        preposition, target = children
        name = _PREPOSITION_NAMES.get(preposition.type, preposition.type.lower())
        return PP(name, target, preposition.column)

    def between(self, children):  # '(in) between A and B'
        first, second = [c for c in children if isinstance(c, NP)]
        return PP("between", first, children[0].column, second)

    def superlative(self, children):
        return PP(children[0].value, children[-1], children[0].column)

    def preposition(self, children):  # "next to", "out of", "inside of", "off of"
        return children[0]

    def it(self, children):
        return It(children[0].column)

    def _region(self, kind, children, value=None, inner=None):
        return Region(kind, _side(children) or value, _first(children, NP), inner,
                      children[0].column)

    def the_side(self, children):
        return self._region("side", children)

    def side_of(self, children):
        return self._region("side_of", children)

    def extreme_position(self, children):
        return self._region("extreme_position", children, value=children[1].value)

    def top_of(self, children):
        return self._region("top_of", children)

    def middle_position(self, children):
        return self._region("middle", children)

    def front_of(self, children):
        return self._region("front_of", children)

    def back_of(self, children):
        return self._region("back_of", children)

    def direction_of(self, children):
        return self._region("direction_of", children)

    def position(self, children):
        return self._region("position", children, inner=children[-1])

    def position_side_of(self, children):
        inner = Region("side_of", _side(children), children[-1], None, children[2].column)
        return self._region("position", children, inner=inner)
