"""Scoring free-text answers against a question's expected answer.

Answers are read for what they name: colours, object kinds (with the instruction lexicon's
synonyms: ball = sphere, block = cube or slab, grey = gray) and sides (left, right, middle;
"in front" = front, "behind" = back). Whatever the question itself names (its landmark) may be
repeated. A colour answer must name exactly the expected colour; an object answer the expected
kind and no other, and its colour if it names one (a description must); a sides answer must put
every object it places on its side ("A is left of B" places both), and place enough of them.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from robofollow.compiler.language.lexicon import VOCABULARY
from robofollow.vqa.answers import Expected, Named

SIDES = {"left": "left", "right": "right", "middle": "middle", "center": "middle",
         "centre": "middle", "between": "middle"}
PHRASES = {"square label": "label", "square labels": "labels", "in front": "front",
           "far left": "left", "far right": "right"}
CLAUSE_BREAKS = re.compile(r"[.;,:]|\b(?:and|while|whereas|but|then)\b")
BLOCK_KINDS = ("cube", "slab")


@dataclass(frozen=True)
class Mention:
    color: str | None
    kind: str | None  # None: a colour alone ("the red one")
    at: int  # token index


@dataclass(frozen=True)
class Verdict:
    correct: bool
    reason: str  # why not, or "" when correct


def _tokens(text: str) -> list[str]:
    text = text.lower()
    for phrase, word in PHRASES.items():
        text = re.sub(rf"\b{phrase}\b", word, text)
    return re.findall(r"[a-z]+", text)


def _word(token: str, terminal: str) -> str | None:
    entry = VOCABULARY.get(token)
    return entry.value if entry is not None and entry.terminal == terminal else None


def _kind(token: str) -> str | None:
    if token in ("label", "labels"):
        return "label"
    return _word(token, "NOUN") or _word(token, "NOUNS")


def mentions(text: str) -> list[Mention]:
    """The things an answer names, in order: a colour with the kind that follows it within
    two words ("the red large cube"), a kind alone, or a colour alone."""
    tokens = _tokens(text)
    found, color, color_at = [], None, -1
    for index, token in enumerate(tokens):
        if (value := _word(token, "COLOR")) is not None:
            if color is not None:
                found.append(Mention(color, None, color_at))
            color, color_at = value, index
            continue
        kind = _kind(token)
        if kind is not None and kind not in ("object", "table"):
            near = color is not None and index - color_at <= 2
            found.append(Mention(color if near else None, kind, index))
            if color is not None and not near:
                found.append(Mention(color, None, color_at))
            color = None
    if color is not None:
        found.append(Mention(color, None, color_at))
    return sorted(found, key=lambda m: m.at)


def _fits(mention: Mention, thing: Named) -> bool:
    """Whether a mention can mean a thing: its colour and kind, where given, agree."""
    kind_ok = mention.kind is None or mention.kind == thing.kind or (
        mention.kind == "block" and thing.kind in BLOCK_KINDS)
    return kind_ok and (mention.color is None or mention.color == thing.color)


def _answer_part(text: str, expected: Expected) -> list[Mention]:
    """The mentions that are not the question's own landmark repeated."""
    return [m for m in mentions(text)
            if not (m.kind is not None and m.color is not None
                    and any(_fits(m, name) for name in expected.question_names))]


def score(text: str, expected: Expected) -> Verdict:
    if expected.type == "color":
        return _score_color(text, expected)
    if expected.type == "object":
        return _score_object(text, expected)
    return _score_sides(text, expected)


def _score_color(text: str, expected: Expected) -> Verdict:
    colors = {m.color for m in _answer_part(text, expected) if m.color is not None}
    if colors == {expected.color}:
        return Verdict(True, "")
    if not colors:
        return Verdict(False, f"names no colour; expected {expected.color}")
    return Verdict(False, f"names {', '.join(sorted(colors))}; expected {expected.color}")


def _score_object(text: str, expected: Expected) -> Verdict:
    thing = expected.object
    named = _answer_part(text, expected)
    kinds = {m.kind for m in named if m.kind is not None}
    colors = {m.color for m in named if m.color is not None}
    wanted = f"expected the {thing.text}"
    if not kinds:
        return Verdict(False, f"names no object; {wanted}")
    if not all(_fits(Mention(None, kind, 0), thing) for kind in kinds):
        return Verdict(False, f"names {', '.join(sorted(kinds))}; {wanted}")
    if colors - {thing.color}:
        return Verdict(False, f"names {', '.join(sorted(colors))}; {wanted}")
    if expected.needs_color and thing.color not in colors:
        return Verdict(False, f"does not give the colour; {wanted}")
    return Verdict(True, "")


def _score_sides(text: str, expected: Expected) -> Verdict:
    placed: dict[int, str] = {}
    named: set[int] = set()
    for clause in CLAUSE_BREAKS.split(text.lower()):
        if not clause.strip():
            continue
        objects = [_which(m, expected) for m in mentions(clause)]
        objects = [o for o in objects if o is not None]
        named.update(objects)
        sides = [SIDES[t] for t in _tokens(clause) if t in SIDES]
        if len(objects) == 2 and len(sides) == 1 and re.search(r"\b(left|right) of\b", clause):
            first, second = objects  # "A is to the left of B"
            placed[first] = sides[0]
            placed[second] = "right" if sides[0] == "left" else "left"
        elif len(objects) == 1 and len(sides) == 1:
            placed[objects[0]] = sides[0]
    for index, side in placed.items():
        if expected.sides[index] != side:
            thing = expected.objects[index]
            return Verdict(False, f"puts the {thing.text} on the {side}; it is on the "
                                  f"{expected.sides[index]} ({expected.text})")
    if expected.template == "relative" and not placed and len(named) == 1:
        (only,) = named  # "Which bowl is on the left?" - "The green one."
        if expected.sides[only] != "left":
            return Verdict(False, f"names the {expected.objects[only].text} as the left one "
                                  f"({expected.text})")
        placed = {only: "left"}
    needed = len(expected.objects) - 1
    if expected.template == "property" and len(named) < len(expected.objects):
        missing = [o.text for i, o in enumerate(expected.objects) if i not in named]
        return Verdict(False, f"does not name the {', '.join(missing)} ({expected.text})")
    if len(placed) < max(1, needed):
        return Verdict(False, f"does not say which is where ({expected.text})")
    return Verdict(True, "")


def _which(mention: Mention, expected: Expected) -> int | None:
    """The expected object a mention picks out among the group, if exactly one."""
    matches = [i for i, thing in enumerate(expected.objects) if _fits(mention, thing)]
    return matches[0] if len(matches) == 1 else None
