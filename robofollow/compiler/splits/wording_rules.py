"""Whether an instruction's referring expressions read as they are scored.

The semantics applies a comparative ('smaller'), superlative ('rightmost'), ordinal or 'middle'
among the candidates the other words of its description leave (grounding.py). That is also
the natural English reading when three rules hold, and a test that breaks one penalises a
policy that reads English well:

order      premodifiers in English order: ordinal / superlative, then size, then colour ('the
           rightmost blue cube', 'the smaller red cube'; not 'the red smaller cube', whose
           natural reading compares over all cubes);
vacuous    a comparison is made among at least two bodies (not 'the smaller blue cube' where
           one cube is blue);
clause     a superlative said after the noun ('the blue cube that is rightmost', 'the blue cube
           on the right') picks the body that is also the superlative of the head noun alone
           (the rightmost cube), the other reading of the clause.

A fourth rule keeps a sentence to one reading where its words allow two:

destination  a destination said right after its object ('move the green cylinder on the right
           side of the blue ball') does not also read as part of the object's description: no
           body is the object so placed already (else the words could ask to move the green
           cylinder that is on the right side of the blue ball, to nowhere said).

`wording_problems` applies them to an instruction and its logical form on one layout; the
split generator rejects a candidate it finds anything in, and the task-list audit reports it.
"""

from __future__ import annotations

from collections.abc import Iterator
from itertools import pairwise

from pydantic import BaseModel

from robofollow.compiler.language import lf, notation
from robofollow.compiler.language.lexicon import WordToken, tokenize
from robofollow.compiler.scene.grounding import Grounder, GroundingError, Unclear
from robofollow.errors import InstructionError

# English premodifier order: lower ranks come first
_RANKS = {"ORDINAL": 0, "MIDDLE": 0, "EXTREME": 0, "LEFT": 0, "RIGHT": 0, "FRONT": 0,
          "BACK": 0, "SIZE": 1, "COLOR": 2}
_RANK_NAMES = ("an ordinal or superlative", "a size word", "a colour")
_SIDE_EXTREMES = {"left": "leftmost", "right": "rightmost"}


def wording_problems(text: str, form: lf.Instruction, grounder: Grounder) -> list[str]:
    """What in `text` (whose meaning is `form`) reads otherwise than it is scored on the
    grounder's layout; empty when nothing does. Text the lexicon cannot read (a hand-edited
    task's) is itself the problem."""
    try:
        tokens = tokenize(text)
    except InstructionError as error:
        return [f"unreadable: column {error.column}: {error.message}"]
    return (order_problems(tokens) + vacuous_comparisons(form, grounder)
            + clause_problems(tokens, form, grounder)
            + destination_problems(tokens, form, grounder))


def order_problems(tokens: list[WordToken]) -> list[str]:
    """Premodifier runs out of English order ('the red smaller cube')."""
    problems = []
    run: list[WordToken] = []
    for token in [*tokens, None]:
        if token is not None and token.type == "NON":
            continue  # 'non-red' ranks as 'red'
        if token is not None and token.type in _RANKS:
            run.append(token)
            continue
        if token is not None and token.type in ("NOUN", "ONE") and len(run) > 1:
            for earlier, later in pairwise(run):
                if _RANKS[earlier.type] > _RANKS[later.type]:
                    problems.append(f"order: '{earlier.text} {later.text}' puts "
                                    f"{_RANK_NAMES[_RANKS[earlier.type]]} before "
                                    f"{_RANK_NAMES[_RANKS[later.type]]} (English says "
                                    f"'{later.text} {earlier.text}')")
        run = []
    return problems


def _refs(node) -> Iterator[lf.Ref]:
    """Every referring expression in a form, landmarks included."""
    if isinstance(node, tuple):
        for item in node:
            yield from _refs(item)
    elif isinstance(node, BaseModel):
        if isinstance(node, lf.Ref):
            yield node
        for name in type(node).model_fields:
            yield from _refs(getattr(node, name))


def comparison_class(ref: lf.Ref, constraint, grounder: Grounder) -> list[str]:
    """The bodies a comparison in `ref` is made among: those of the noun that the
    description's other, plain words fit (less a 'closest to' landmark)."""
    plain = [c for c in ref.constraints if not isinstance(c, lf.COMPARATIVES)]
    found = [b for b in grounder.domain(ref.noun)
             if all(grounder.satisfies(b, c) for c in plain)]
    if isinstance(constraint, lf.NearestIs):
        landmark = grounder.resolve(constraint.landmark)
        found = [b for b in found if b != landmark]
    return found


def vacuous_comparisons(node: lf.Instruction | lf.Ref, grounder: Grounder) -> list[str]:
    """Comparisons made among fewer than two bodies, in a form or one description."""
    problems = []
    for ref in _refs(node):
        for constraint in ref.constraints:
            if not isinstance(constraint, lf.COMPARATIVES):
                continue
            try:
                among = comparison_class(ref, constraint, grounder)
            except GroundingError:
                continue  # a landmark that does not ground: the grounding check says so
            if len(among) < 2:
                what = ", ".join(among) or "nothing"
                problems.append(f"vacuous: '{notation.constraint(constraint)}' in "
                                f"'{notation.ref(ref)}' compares {len(among)} "
                                f"bod{'y' if len(among) == 1 else 'ies'} ({what})")
    return problems


def _clause_extremes(tokens: list[WordToken]) -> set[str]:
    """Superlatives said after a noun: 'cube that is rightmost', 'cube on the right', 'cube
    in the frontmost position'."""
    found = set()
    types = [t.type for t in tokens]
    for index, token in enumerate(tokens):
        if token.type != "NOUN":
            continue
        after = types[index + 1:index + 5]
        if after[:3] in (["THAT", "IS", "EXTREME"], ["WHICH", "IS", "EXTREME"]) or after[:3] == ["IN", "THE", "EXTREME"] and after[3:4] == ["POSITION"]:
            found.add(tokens[index + 3].value)
        elif (after[:2] == ["ON", "THE"] and after[2:3] in (["LEFT"], ["RIGHT"])
              and after[3:4] not in (["SIDE"], ["OF"])):
            found.add(_SIDE_EXTREMES[tokens[index + 3].value])
    return found


def clause_problems(tokens: list[WordToken], form: lf.Instruction,
                    grounder: Grounder) -> list[str]:
    """Superlatives after the noun whose reading over the head noun alone picks another
    body than the reading over what the other words leave."""
    extremes = _clause_extremes(tokens)
    problems = []
    for ref in _refs(form):
        plain = [c for c in ref.constraints if not isinstance(c, lf.COMPARATIVES)]
        for constraint in ref.constraints:
            if not (isinstance(constraint, lf.ExtremeIs) and constraint.extreme in extremes
                    and plain):
                continue
            try:
                restricted = grounder.compare(comparison_class(ref, constraint, grounder),
                                              constraint, ref)
            except GroundingError:
                continue  # the grounding check reports it
            try:
                overall = grounder.compare(grounder.domain(ref.noun), constraint, ref)
            except GroundingError as error:  # a tie: the head noun alone picks no one body
                overall = list(error.candidates)
            if not restricted or not set(restricted) <= set(overall) or len(overall) != 1:
                problems.append(
                    f"clause: '{notation.ref(ref)}' is scored as {', '.join(restricted)}, "
                    f"but the {constraint.extreme} {ref.noun} is "
                    f"{' or '.join(overall) or 'no body'}")
    return problems


def destination_problems(tokens: list[WordToken], form: lf.Instruction,
                         grounder: Grounder) -> list[str]:
    """Placements whose destination, said right after the object, also reads as part of the
    object's description: some body fits the object's words and stands so already. ('Pick
    up X and place it ...' says the destination after a pronoun; a route said between them,
    'over Y', parts them too.)"""
    if any(token.type == "IT" for token in tokens):
        return []
    problems = []
    for place in (command for _, command in lf.commands(form)
                  if isinstance(command, lf.Place)):
        if any(waypoint.mode == "via" for waypoint in place.route):
            continue
        destination = place.destination
        try:
            read = lf.Ref(noun=place.object.noun, constraints=(*place.object.constraints, lf.Related(
                relation=destination.relation, landmark=destination.landmark)))
            found = ', '.join(grounder.fitting(read))
        except Unclear as error:  # a body a viewer could see standing there already
            found = f"{', '.join(error.candidates)} may be ({error.message})"
        except (ValueError, GroundingError):  # a landmark no description relation takes
            continue
        if found:
            problems.append(f"destination: '{notation.ref(place.object)}' then "
                            f"'{destination.relation} {notation.ref(destination.landmark)}' "
                            f"also reads as '{notation.ref(read)}', which {found} is")
    return problems
