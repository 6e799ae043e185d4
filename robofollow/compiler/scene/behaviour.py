"""What an instruction asks for, grounded: steps (arm, action, objects, route, final yaw), and
for a conditional the condition's value and both branches."""

from __future__ import annotations

from typing import Literal

from robofollow.compiler.language import lf
from robofollow.compiler.scene.model import Model


class Step(Model):
    """One grounded command."""

    action: Literal["pick", "place", "push"]
    arm: lf.Arm | None
    source: str
    relation: lf.PlaceRelation | None = None
    target: str | None = None
    waypoints: tuple[tuple[Literal["via", "avoid"], str], ...] = ()
    yaw_degrees: float | None = None


class Behaviour(Model):
    """What an instruction asks for in one layout."""

    steps: tuple[Step, ...]
    condition: bool | None = None  # a conditional's condition, evaluated in the layout
    branch: Literal["then", "otherwise"] | None = None
    other: tuple[Step, ...] | None = None  # the branch not taken, when it grounds


def describe_steps(steps: tuple[Step, ...]) -> str:
    """Steps in the spec's `expect` syntax."""
    parts = []
    for step in steps:
        words = [step.action, step.arm or "?", step.source]
        if step.action == "place":
            words += [step.relation, step.target]
            words += [f"{mode} {body}" for mode, body in step.waypoints]
            if step.yaw_degrees is not None:
                words.append(f"yaw {step.yaw_degrees:g}")
        elif step.action == "push":
            words += ["towards", step.target]
        parts.append(" ".join(words))
    return ", ".join(parts) or "nothing"


def describe(behaviour: Behaviour) -> str:
    prefix = f"{behaviour.branch}: " if behaviour.branch else ""
    return prefix + describe_steps(behaviour.steps)
