"""What a stage evaluator returns, and the words the evaluators share."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class Outcome:
    intent: bool
    execution: bool
    frame: int | None  # where the stage's intent was first met (or the deciding frame)
    reason: str


def cm(metres: float) -> str:
    """A distance in words: '1.5 cm'."""
    return f"{metres * 100:.1f} cm"


# what counts as going for a step's object: a grasp or a close (for a push: a grasp or a
# push); brushing an object on the way is judged by its effect, in the finish
GRASPING = ("grasp", "close")
GOING_FOR = {"pick": GRASPING, "place": GRASPING, "push": ("grasp", "push")}
