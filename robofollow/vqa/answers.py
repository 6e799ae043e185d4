"""What a question expects, as data: a colour, an object, or objects with their sides.

An object is named by its colour and kind ("red cylinder"); `sides` lists objects from left
to right, each with the side word it is expected with ("left", "middle", "right").
"""

from __future__ import annotations

from typing import Literal

from pydantic import ConfigDict, ValidationInfo, field_validator
from pydantic_core import PydanticCustomError

from robofollow.compiler.scene.model import Model
from robofollow.compiler.scene.world import World

KIND_WORDS = {"label": "square label"}  # how a body kind is said, where not by its name
NEEDS = {"color": "color", "object": "object", "sides": "objects"}  # the field each type of
#   answer needs


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
    model_config = ConfigDict(validate_default=True)  # what a type needs may be left out

    @field_validator(*NEEDS.values())
    @classmethod
    def _given(cls, value, info: ValidationInfo):
        """The field this type of answer needs is given."""
        kind = info.data.get("type")
        if not value and NEEDS.get(kind) == info.field_name:
            raise PydanticCustomError("needed", "an answer of type {kind} needs it",
                                      {"kind": kind})
        return value

    @field_validator("sides")
    @classmethod
    def _parallel(cls, sides: tuple[str, ...], info: ValidationInfo) -> tuple[str, ...]:
        """As many sides as objects."""
        objects = info.data.get("objects")
        if objects is not None and len(sides) != len(objects):
            raise PydanticCustomError("parallel", "{sides} sides for {objects} objects",
                                      {"sides": len(sides), "objects": len(objects)})
        return sides

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
