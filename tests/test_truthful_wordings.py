"""Every shipped L2/L3 wording reads as it is scored, checked here independently of the
generator and of compiler/splits/wording_rules.py: adjectives in English order (superlative or
ordinal, then size, then colour), every comparison made among at least two bodies (counted
from the layout's bodies by kind and colour), and a superlative after the noun ('the blue cube
that is rightmost') naming the body that is also the superlative of all bodies of the noun."""

from __future__ import annotations

import re

import pytest
from pydantic import BaseModel

from robofollow.benchmark.pipeline import compile_specs
from robofollow.compiler.language import lf
from robofollow.compiler.scene.world import World
from robofollow.resources import builtin_specs

COLOURS = "red|green|blue|yellow|orange|purple|pink|white|black|gray|grey|brown"
SIZES = "larger|smaller|bigger|largest|smallest|big|small|large|little"
POSITIONS = "leftmost|rightmost|frontmost|backmost|middle|second|third|fourth|fifth|left|right"
OUT_OF_ORDER = re.compile(rf"\b(?:(?:non-)?(?:{COLOURS}) (?:{SIZES}|{POSITIONS})"
                          rf"|(?:{SIZES}) (?:{POSITIONS}))\b")
AFTER_NOUN = re.compile(r"\b(cube|cylinder|ball|sphere|block|object|item|slab|bar|bowl|label) "
                        r"(?:that is (leftmost|rightmost)|on the (left|right)(?! side| of))\b")
NOUNS = {"ball": "sphere", "item": "object", "bar": "slab"}
SIDES = {"left": "leftmost", "right": "rightmost"}


def _refs(node):
    if isinstance(node, tuple):
        for item in node:
            yield from _refs(item)
    elif isinstance(node, BaseModel):
        if isinstance(node, lf.Ref):
            yield node
        for name in type(node).model_fields:
            yield from _refs(getattr(node, name))


def _of_noun(world: World, noun: str) -> list[str]:
    return [b for b, body in world.bodies.items()
            if (noun == "object" and not body.fixture) or body.kind == noun
            or (noun == "block" and body.kind in ("cube", "slab"))]


def _class(world: World, ref: lf.Ref) -> list[str]:
    """The bodies of the noun with the description's colours (no other plain words occur)."""
    colours = [c for c in ref.constraints if isinstance(c, lf.ColorIs)]
    return [b for b in _of_noun(world, ref.noun)
            if all((world.bodies[b].color == c.color) != c.negated for c in colours)]


def _extreme(world: World, bodies: list[str], extreme: str) -> str | None:
    """The body farthest to one side, if it leads the next by a centimetre (else a tie)."""
    sign = -1 if extreme == "leftmost" else 1
    ranked = sorted(bodies, key=lambda b: -sign * world.poses[b].x)
    if len(ranked) > 1 and sign * (world.poses[ranked[0]].x - world.poses[ranked[1]].x) < 0.01:
        return None
    return ranked[0]


@pytest.fixture(scope="module")
def reworded():
    compiled = compile_specs(builtin_specs())
    return [(t, World(compiled.spec.scenes[t.scene], t.layout)) for t in compiled.splits.tasks
            if t.level in ("L2", "L3")]


def test_adjectives_follow_english_order(reworded):
    wrong = [(t.id, m.group()) for t, _ in reworded
             for m in [OUT_OF_ORDER.search(t.instruction.lower())] if m]
    assert not wrong


def test_every_comparison_is_made_among_two_bodies_or_more(reworded):
    vacuous = []
    for task, world in reworded:
        for ref in _refs(task.form):
            if not any(isinstance(c, lf.COMPARATIVES) for c in ref.constraints):
                continue
            plain = [c for c in ref.constraints if not isinstance(c, lf.COMPARATIVES)]
            assert all(isinstance(c, lf.ColorIs) for c in plain), (task.id, ref)
            if len(_class(world, ref)) < 2:
                vacuous.append((task.id, task.instruction))
    assert not vacuous


def test_a_superlative_after_the_noun_agrees_with_the_head_noun_alone(reworded):
    checked = 0
    for task, world in reworded:
        for match in AFTER_NOUN.finditer(task.instruction.lower()):
            noun = NOUNS.get(match.group(1), match.group(1))
            extreme = match.group(2) or SIDES[match.group(3)]
            for ref in _refs(task.form):
                if ref.noun != noun or lf.ExtremeIs(extreme=extreme) not in ref.constraints:
                    continue
                checked += 1
                scored = _extreme(world, _class(world, ref), extreme)
                assert scored is not None, task.id
                assert scored == _extreme(world, _of_noun(world, noun), extreme), task.id
    assert checked > 0
