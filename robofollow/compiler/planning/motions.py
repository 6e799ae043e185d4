"""Behaviours as motions, and the training repertoire they are checked against.

A step's motion is what a policy has to do, not whom it is done to: the arm, the action, the
handled body's shape and size, where it is picked (the grasp point, or where a push starts,
and what the body rests on), where it is put (the release point, or where a push ends), the
route (the points passed over) and the final yaw. Points come from the expert's plan of the
step alone. Two motions are equivalent when every part agrees within the tolerances below.

A test step is in the repertoire when some training step of its scene has an equivalent
motion. L0 and L1 ask for a trained behaviour as a whole, so their steps must match one
training task's steps in order; L2 and L3 may compose trained steps anew, so each step only
needs some trained step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from robofollow.compiler.planning.plans import plan
from robofollow.compiler.scene.behaviour import Behaviour, Step, describe_steps
from robofollow.compiler.scene.spec import Scene
from robofollow.compiler.scene.world import World

MOTION_XY_TOLERANCE = 0.03  # m: pick, put and route points this close in the plane agree
MOTION_Z_TOLERANCE = 0.01  # m: ... and this close in height
SIZE_TOLERANCE = 0.006  # m: handled bodies whose half extents differ by at most this agree
YAW_TOLERANCE = 1.0  # deg
# shapes a parallel gripper handles alike: flat-sided bodies stand and are gripped across two
# faces (a cylinder across its sides); a sphere rolls
GRIP_SHAPES = {"cube": "upright", "slab": "upright", "cylinder": "upright", "sphere": "round"}
COMPOSING_LEVELS = ("L2", "L3")

Point = tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class Motion:
    arm: str | None
    action: str
    shape: str
    size: tuple[float, float, float]  # the handled body's half extents
    support: str  # what it rests on when picked: "table", "on" another body, "in" a bowl
    pick: Point
    put: Point | None
    route: tuple[Point, ...]
    yaw: float | None


def motion(step: Step, world: World) -> Motion:
    """The motion of one step in a world."""
    body = world.bodies[step.source]
    points = plan(Behaviour(steps=(step.model_copy(update={"arm": "left"}),)), world).points
    named = {p.name: p.position for p in points}
    if step.action == "push":
        pick, put = named["push_start"], named["push_end"]
    else:
        pick, put = named["grasp"], named.get("place")
    return Motion(arm=step.arm, action=step.action, shape=GRIP_SHAPES.get(body.kind, body.kind),
                  size=body.half_extents, support=world.layout.placed[step.source].relation,
                  pick=pick, put=put, route=tuple(p.position for p in points if p.name == "via"),
                  yaw=step.yaw_degrees)


def _near(a: Point | None, b: Point | None) -> bool:
    if a is None or b is None:
        return a is b
    return (math.hypot(a[0] - b[0], a[1] - b[1]) <= MOTION_XY_TOLERANCE
            and abs(a[2] - b[2]) <= MOTION_Z_TOLERANCE)


def differences(test: Motion, trained: Motion) -> list[str]:
    """The parts of `test` that `trained` does not do alike (empty: equivalent)."""
    parts = []
    if test.arm != trained.arm:
        parts.append("arm")
    if test.action != trained.action:
        parts.append("action")
    if test.shape != trained.shape or any(abs(a - b) > SIZE_TOLERANCE
                                          for a, b in zip(test.size, trained.size, strict=True)):
        parts.append("object")
    if test.support != trained.support or not _near(test.pick, trained.pick):
        parts.append("pick location")
    if not _near(test.put, trained.put):
        parts.append("put location")
    if len(test.route) != len(trained.route) or not all(
            _near(a, b) for a, b in zip(test.route, trained.route, strict=True)):
        parts.append("route")
    if (test.yaw is None) != (trained.yaw is None) or (
            test.yaw is not None and abs(test.yaw - trained.yaw) > YAW_TOLERANCE):
        parts.append("yaw")
    return parts


def _cm(point: Point) -> str:
    return "(" + ", ".join(f"{100 * v:.1f}" for v in point) + ") cm"


def named(part: str, m: Motion) -> str:
    """A part's name as a message gives it: a push's locations are where it starts and ends."""
    pushed = {"pick location": "push start", "put location": "push end"}
    return pushed.get(part, part) if m.action == "push" else part


def shown(part: str, m: Motion) -> str:
    """One part of a motion, in words."""
    if part == "arm":
        return f"the {m.arm or 'unnamed'} arm"
    if part == "action":
        return m.action
    if part == "object":
        return f"{' x '.join(f'{200 * h:.1f}' for h in m.size)} cm, {m.shape}"
    if part == "pick location":
        return f"from {'the table' if m.support == 'table' else m.support + ' a body'} at " \
               f"{_cm(m.pick)}"
    if part == "put location":
        return f"to {_cm(m.put)}" if m.put else "none (held up)"
    if part == "route":
        return "over " + (", ".join(map(_cm, m.route)) or "nothing")
    return f"yaw {m.yaw:g}" if m.yaw is not None else "any yaw"


@dataclass(frozen=True, slots=True)
class Trained:
    """A training task's steps as motions."""

    label: str
    layout: str
    steps: tuple[Step, ...]
    motions: tuple[Motion, ...]


class Repertoire:
    """The motions a scene's training tasks perform, each on its own layout."""

    def __init__(self, scene: Scene, training: dict[str, Behaviour]):
        self.trained = []
        for task in scene.tasks:
            if task.label not in training:  # a task that failed its checks
                continue
            world, steps = World(scene, task.layout), training[task.label].steps
            self.trained.append(Trained(task.label, task.layout, steps,
                                        tuple(motion(s, world) for s in steps)))
        self.steps = [(t, i) for t in self.trained for i in range(len(t.steps))]
        # keyed by the world's identity; the entry keeps the world alive (as Grounder does)
        self._motions: dict[tuple[int, Step], tuple[World, Motion]] = {}

    def motion(self, step: Step, world: World) -> Motion:
        """`motion` (memoised: a world does not change, and many candidates share a step)."""
        cached = self._motions.get((id(world), step))
        if cached is None or cached[0] is not world:
            cached = self._motions[id(world), step] = world, motion(step, world)
        return cached[1]

    def covers(self, behaviour: Behaviour, world: World, compose: bool) -> bool:
        return self.missing(behaviour, world, compose) is None

    def missing(self, behaviour: Behaviour, world: World, compose: bool) -> str | None:
        """None when training performs the behaviour (step by step if `compose`, else as a
        whole); otherwise what is new, against the nearest training motion."""
        motions = [self.motion(s, world) for s in behaviour.steps]
        for index, m in enumerate(motions):
            if not any(not differences(m, t.motions[i]) for t, i in self.steps):
                return self._new_step(behaviour, index, m)
        if compose or any(len(t.motions) == len(motions) and all(
                not differences(a, b) for a, b in zip(motions, t.motions, strict=True))
                for t in self.trained):
            return None
        return (f"{describe_steps(behaviour.steps)}: every step is trained, but no training task "
                "performs them together in this order (composition is what L2 and L3 test)")

    def _new_step(self, behaviour: Behaviour, index: int, m: Motion) -> str:
        if not self.steps:
            return f"{describe_steps(behaviour.steps)}: the scene has no checked training task"
        def distance(entry):
            trained = entry[0].motions[entry[1]]
            parts = differences(m, trained)
            return ("action" in parts, len(parts),
                    math.hypot(m.pick[0] - trained.pick[0], m.pick[1] - trained.pick[1]))

        trained, at = min(self.steps, key=distance)
        nearest = trained.motions[at]
        parts = differences(m, nearest)
        which = f"step {index + 1} " if len(behaviour.steps) > 1 else ""
        new = "; ".join(f"new {named(part, m)}: {shown(part, m)} (trained: "
                        f"{shown(part, nearest)})" for part in parts)
        return (f"{which}{describe_steps((behaviour.steps[index],))}: no training step moves "
                f"alike; against the nearest, {trained.label} "
                f"({describe_steps((trained.steps[at],))} on {trained.layout}), {new}")

    def as_trained(self, behaviour: Behaviour, world: World, label: str) -> bool:
        """Whether `behaviour` moves as training task `label` does, step for step (a test of
        the trained motion for the trained sentence: a memorised replay passes it)."""
        trained = next((t for t in self.trained if t.label == label), None)
        motions = [self.motion(s, world) for s in behaviour.steps]
        return trained is not None and len(motions) == len(trained.motions) and all(
            not differences(a, b) for a, b in zip(motions, trained.motions, strict=True))

    def arm_for(self, behaviour: Behaviour, index: int, world: World) -> str | None:
        """The one arm training performs step `index` of `behaviour` with (every other part
        alike), or None when it uses none or both."""
        m = self.motion(behaviour.steps[index], world)
        arms = {t.motions[i].arm for t, i in self.steps
                if differences(m, t.motions[i]) in ([], ["arm"])}
        return arms.pop() if len(arms) == 1 else None
