"""Two labels of an L1 or L3 test task against the training task it derives from, which answer
different questions and are never one word:

- `motion` ("moved" / "as-trained", the task's own): whether the expert's motion changes
  (another grip, pick or put place, route or yaw), which a policy must produce anew;
- `object_moved` (true / false): whether a body the task handles stands elsewhere than the
  training task's did (more than OBSERVATION_TOLERANCE apart, step by step), which a policy
  must see.

A task that moves its object changes its motion (the grasp moves with the object), but a task
can change its motion and leave its object in place: the same cube put in a bowl that moved, or
carried around a slab that did. Both are None at L0 and L2 and for listed tests."""

from __future__ import annotations

import math
from collections.abc import Mapping

from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.compiler.scene.observation import OBSERVATION_TOLERANCE
from robofollow.compiler.scene.spec import MOTION_LEVELS, Scene
from robofollow.compiler.scene.world import World
from robofollow.compiler.splits.tasks import TestTask


def _sources(world: World, behaviour: Behaviour) -> list[tuple[float, float, float]]:
    """Where each step's handled body stands."""
    return [(pose.x, pose.y, pose.z) for pose in (world.poses[step.source]
                                                 for step in behaviour.steps)]


def object_moved(scene: Scene, task: TestTask, training: Mapping[str, Behaviour]) -> bool | None:
    """Whether the task's handled bodies stand elsewhere than its training task's (None where
    the task has no training task to move from: L0, L2, listed tests)."""
    origin = next((t for t in scene.tasks if t.label == task.origin), None)
    if task.level not in MOTION_LEVELS or origin is None:
        return None
    now = _sources(World(scene, task.layout), task.behaviour)
    then = _sources(World(scene, origin.layout), training[task.origin])
    return len(now) != len(then) or any(math.dist(a, b) > OBSERVATION_TOLERANCE
                                        for a, b in zip(now, then, strict=False))


def labels(scene: Scene, task: TestTask, training: Mapping[str, Behaviour]) -> dict:
    """The task's labels as the task files write them: {"motion", "object_moved"}."""
    return {"motion": task.motion, "object_moved": object_moved(scene, task, training)}
