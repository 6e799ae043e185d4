"""What a question expects, as data: a colour, an object, or objects with their sides.

An object is named by its colour and kind ("red cylinder"); `sides` lists objects from left
to right, each with the side word it is expected with ("left", "middle", "right").
"""

from __future__ import annotations

from typing import Literal

from robofollow.compiler.scene.model import Model
from robofollow.compiler.scene.world import World

KIND_WORDS = {"label": "square label"}  # how a body kind is said, where not by its name


class Named(Model):
    color: str
    kind: str

    @property
    def text(self) -> str:
        return f"{self.color} {KIND_WORDS.get(self.kind, self.kind)}"


class Expected(Model):
    """`color`: the colour alone; `object`: one object (`needs_color`: a description must
    give the colour too); `sides`: several objects, each with its side."""
    type: Literal["color", "object", "sides"]
    color: str | None = None
    object: Named | None = None
    needs_color: bool = False
    objects: tuple[Named, ...] = ()
    sides: tuple[str, ...] = ()  # parallel to objects
    question_names: tuple[Named, ...] = ()  # what the question itself names (its landmark)
    template: str = ""  # the question's template, for how sides may be stated

    @property
    def text(self) -> str:
        """The reference answer, in words."""
        if self.type == "color":
            return self.color
        if self.type == "object":
            return f"the {self.object.text}"
        parts = [f"the {o.text} is on the {side}" for o, side in zip(self.objects, self.sides, strict=True)]
        return (", ".join(parts[:-1]) + " and " + parts[-1]) if len(parts) > 1 else parts[0]


def named(world: World, body: str) -> Named:
    spec = world.bodies[body]
    return Named(color=spec.color, kind=spec.kind)


def side_words(count: int) -> tuple[str, ...]:
    """The side words of `count` objects ordered left to right."""
    return {2: ("left", "right"), 3: ("left", "middle", "right")}[count]
