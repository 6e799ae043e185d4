"""Referring expressions: a noun phrase and the links of its modifier chain -> `lf.Ref`.

One link at a time (`meanings`): a prepositional phrase, a predicate of a relative clause or
a particle becomes a Meaning; the semantics (semantics.py) decides which links describe the
object and which are its destination, route or target, and `extend` folds the describing
ones into the reference. Errors point at the word that causes them.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, fields, is_dataclass
from typing import get_args

from pydantic import ValidationError

from robofollow.compiler.language import lf
from robofollow.compiler.language.syntax import NP, PP, It, Link, Predicate, Region
from robofollow.errors import UnsupportedConstructError

_WORD = re.compile(r"[A-Za-z'’-]+")
_NOUN_PARENTS = {"cube": "block", "slab": "block"}
CONTAINERS = frozenset({"bowl"})
_SIDE_RELATIONS = {"left": "left_of", "right": "right_of"}
_SIDE_EXTREMES = {"left": "leftmost", "right": "rightmost"}
_KINDS = frozenset(get_args(lf.Noun)) - {"object", "block", "table"}  # what a body can be

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


class ReferringExpressions:
    """The pass over one instruction's referring expressions (holds the text for error
    messages, and what a later 'one' stands for)."""

    def __init__(self, text: str):
        self.text = text
        self.domain: lf.Ref | None = None  # 'among the <nouns>': what a later 'one' stands for
        self.said: list[tuple[int, str]] = []  # (column, noun) of every noun the text names

    def read_nouns(self, syntax) -> None:
        """Note the nouns an instruction's syntax names, for the 'one's that follow them."""
        self.said = sorted(_nouns_named(syntax))

    def fail(self, column: int, message: str) -> UnsupportedConstructError:
        return UnsupportedConstructError(message, text=self.text, column=column,
                                         length=self._word_length(column))

    def _word_length(self, column: int) -> int:
        word = _WORD.match(self.text, column - 1)
        return len(word.group()) if word else 1

    # ---------------------------------------------------------------- noun phrases
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
        if np.head == "one" and domain is None:
            domain = self.antecedent(np.column)
        if np.head == "one" and domain is not None:
            constraints.extend(domain.constraints)
        try:
            return self.extend(self.head_noun(np, domain), constraints, meanings)
        except ValueError as error:  # e.g. two ordinals for one object
            raise self.fail(np.column, _reason(error)) from None

    def antecedent(self, column: int) -> lf.Ref | None:
        """What a 'one' outside 'among' stands for: a body of any kind named before it (a
        reader takes whichever reading refers; two that refer make it ambiguous), or any
        body when the text names no kind before it, or opens with a 'one' (which stands for
        any body, and so may the 'one's after it)."""
        said = [noun for at, noun in self.said if at < column]
        if not said or said[0] == "one" or "object" in said:
            return None
        named = set(said) - {"one"}
        if "block" in named:
            named |= {"cube", "slab"}
        for noun in ("block", *sorted(named)):
            if named == ({"cube", "slab"} if noun == "block" else {noun}):
                return lf.Ref(noun=noun)
        return lf.Ref(noun="object", constraints=tuple(
            lf.NotKind(noun=kind) for kind in sorted(_KINDS - named)))

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
                relation = "in" if landmark.noun in CONTAINERS else "on"
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


def _nouns_named(node) -> list[tuple[int, str]]:
    """(column, noun) of every noun phrase in a syntax tree, 'one' and 'the rightmost ball'
    included, the table left out."""
    if isinstance(node, (list, tuple)):
        return [named for item in node for named in _nouns_named(item)]
    if not is_dataclass(node):
        return []
    found = []
    if isinstance(node, NP) and node.head != "table":
        found.append((node.column, node.head))
    if isinstance(node, Predicate) and node.noun not in (None, "one", "table"):
        found.append((node.column, node.noun))
    for field in fields(node):
        found.extend(_nouns_named(getattr(node, field.name)))
    return found


def _reason(error: ValueError) -> str:
    """What a failed check of a logical form says (pydantic's first error, unwrapped)."""
    if isinstance(error, ValidationError):
        first = error.errors(include_url=False)[0]
        cause = first.get("ctx", {}).get("error")
        return str(cause) if cause is not None else first["msg"]
    return str(error)
