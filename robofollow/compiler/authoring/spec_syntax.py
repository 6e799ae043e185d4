"""The spec grammar (grammar/spec.lark): a file's text -> small syntax records, built by a
Transformer applied inline while the LALR parser reduces (spec_parse.py parses, and says
where and why a text does not).

The records keep the tokens as written (each knows its line and column, for errors); what they
mean is checked in spec_loader.py and layouts.py.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

from lark import Lark, Token, Transformer, v_args

from robofollow.compiler.language.lark_tables import cached_lark
from robofollow.resources import grammar_text

# ---------------------------------------------------------------- values


@dataclass(frozen=True, slots=True)
class Number:
    token: Token


@dataclass(frozen=True, slots=True)
class Name:
    token: Token


@dataclass(frozen=True, slots=True)
class Values:
    """(a, b, ...)"""

    items: tuple[Value, ...]


@dataclass(frozen=True, slots=True)
class Interval:
    """[low, high]"""

    low: Token
    high: Token


Value = Number | Name | Values | Interval


@dataclass(frozen=True, slots=True)
class Attribute:
    key: Token
    value: Value


@dataclass(frozen=True, slots=True)
class Coordinates:
    x: Token
    y: Token


# ---------------------------------------------------------------- scene items


@dataclass(frozen=True, slots=True)
class PointNode:
    name: Token
    coordinates: Coordinates


@dataclass(frozen=True, slots=True)
class BodyNode:
    fixture: bool
    name: Token
    kind: Token
    attributes: tuple[Attribute, ...]


@dataclass(frozen=True, slots=True)
class JitterNode:
    target: Token  # a body, or '*'
    attributes: tuple[Attribute, ...]


@dataclass(frozen=True, slots=True)
class SettingNode:
    name: Token
    value: Value


@dataclass(frozen=True, slots=True)
class LayoutOp:
    """One line of a layout: at, move (a position), on, in_, put_on, put_in, swap (another
    body), remove, recolor (a colour word and its rgb)."""

    kind: str
    body: Token
    other: Token | None = None
    position: Coordinates | Token | None = None  # coordinates, or a point's name
    colour: Token | None = None
    rgb: Attribute | None = None


@dataclass(frozen=True, slots=True)
class LayoutNode:
    name: Token
    base: Token | None  # `from` this layout
    ops: tuple[LayoutOp, ...]


@dataclass(frozen=True, slots=True)
class Waypoint:
    kind: Token  # via, avoid
    name: Token


@dataclass(frozen=True, slots=True)
class StepNode:
    action: str  # pick, place, push
    arm: Token
    source: Token
    target: Token | None = None
    relation: Token | None = None
    waypoints: tuple[Waypoint, ...] = ()
    yaw: Token | None = None


@dataclass(frozen=True, slots=True)
class ExpectNode:
    branch: Token | None
    steps: tuple[StepNode, ...]


@dataclass(frozen=True, slots=True)
class TaskNode:
    label: Token
    layout: Token
    strings: tuple[Token, ...]  # with their quotes
    expect: ExpectNode | None


@dataclass(frozen=True, slots=True)
class TestNode:
    level: Token
    name: Token
    layout: Token
    string: Token  # with its quotes
    expect: ExpectNode | None


@dataclass(frozen=True, slots=True)
class SplitNode:
    level: Token
    attributes: tuple[Attribute, ...]


SceneItem = PointNode | BodyNode | JitterNode | SettingNode | LayoutNode | TaskNode | TestNode \
    | SplitNode


@dataclass(frozen=True, slots=True)
class SceneNode:
    name: Token
    title: Token  # with its quotes
    items: tuple[SceneItem, ...]


# ---------------------------------------------------------------- the transformer


@v_args(inline=True)
class _ToNodes(Transformer):
    def start(self, *scenes):
        return list(scenes)

    def scene(self, name, title, *items):
        return SceneNode(name, title, items)

    def point(self, name, coordinates):
        return PointNode(name, coordinates)

    def body(self, kind_word, name, kind, *attributes):
        return BodyNode(kind_word == "fixture", name, kind, attributes)

    def body_kind(self, word):  # object, fixture
        return word

    def jitter(self, target, *attributes):
        return JitterNode(target, attributes)

    def setting(self, name, value):
        return SettingNode(name, value)

    def attribute(self, key, value):
        return Attribute(key, value)

    def number(self, token):
        return Number(token)

    def name(self, token):
        return Name(token)

    def values(self, *items):
        return Values(items)

    def interval(self, low, high):
        return Interval(low, high)

    def coordinates(self, x, y):
        return Coordinates(x, y)

    def layout(self, name, base, *ops):
        return LayoutNode(name, base, ops)

    def at(self, body, position):
        return LayoutOp("at", body, position=position)

    def move(self, body, position):
        return LayoutOp("move", body, position=position)

    def on(self, body, other):
        return LayoutOp("on", body, other)

    def in_(self, body, other):
        return LayoutOp("in_", body, other)

    def put_on(self, body, other):
        return LayoutOp("put_on", body, other)

    def put_in(self, body, other):
        return LayoutOp("put_in", body, other)

    def swap(self, body, other):
        return LayoutOp("swap", body, other)

    def remove(self, body):
        return LayoutOp("remove", body)

    def recolor(self, body, colour, rgb):
        return LayoutOp("recolor", body, colour=colour, rgb=rgb)

    def rgb(self, key, _equals, value):  # rgb=(r, g, b) of a recolor, an attribute as written
        return Attribute(key, value)

    def task(self, label, layout, *strings_and_expect):
        *strings, expect = strings_and_expect
        return TaskNode(label, layout, tuple(strings), expect)

    def test(self, level, name, layout, string, expect):
        return TestNode(level, name, layout, string, expect)

    def expect(self, branch, *steps):
        return ExpectNode(branch, steps)

    def branch(self, word):  # then, otherwise
        return word

    def pick(self, arm, source):
        return StepNode("pick", arm, source)

    def place(self, arm, source, relation, target, *waypoints_and_yaw):
        *waypoints, yaw = waypoints_and_yaw
        return StepNode("place", arm, source, target, relation, tuple(waypoints), yaw)

    def push(self, arm, source, target):
        return StepNode("push", arm, source, target)

    def relation(self, word):
        return word

    def waypoint(self, kind, name):
        return Waypoint(kind, name)

    def yaw(self, number):
        return number

    def split(self, level, *attributes):
        return SplitNode(level, attributes)


# ---------------------------------------------------------------- the parser


@cache
def spec_parser() -> Lark:
    """The spec grammar's LALR parser, building the records above as it reduces."""
    return cached_lark("spec", grammar_text("spec.lark"), strict=True, transformer=_ToNodes())
