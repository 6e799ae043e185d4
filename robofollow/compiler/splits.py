"""Split generation from rules: candidates for each level, each kept or rejected with a reason.

- L0: each training task's first paraphrase on its training layout.
- L1: training first paraphrases on the split rule's changed layouts, kept when they still
  ground to exactly one behaviour inside the training repertoire.

A behaviour is inside the repertoire when some training task of the scene performs the same
steps (arm, action, source, relation, target, bodies passed over, final yaw) and every route
waypoint still lies on the way from the source to the destination, as it does in training.
"""

from __future__ import annotations

import hashlib
from typing import Literal

from robofollow.compiler import lf
from robofollow.compiler.grounding import Behaviour, GroundingError, Step, ground
from robofollow.compiler.spec import Level, Model, Scene, Spec
from robofollow.compiler.training import describe
from robofollow.compiler.world import World

ROUTE_CORRIDOR = 0.03  # m: a waypoint may lie this far outside the source-destination x span
COLUMN_TOLERANCE = 0.03  # m: bodies this close in x stand in one column (a detour's choice)


class TestTask(Model):
    id: str
    scene: str
    level: Level
    layout: str
    instruction: str
    form: lf.Instruction
    behaviour: Behaviour
    origin: str  # the training task it derives from
    wording: str  # "training", or the generator that reworded it


class Rejection(Model):
    scene: str
    level: Level
    layout: str
    instruction: str
    origin: str
    reason: str


class Splits(Model):
    tasks: tuple[TestTask, ...]
    rejected: tuple[Rejection, ...]

    def of(self, scene: str, level: Level) -> list[TestTask]:
        return [t for t in self.tasks if t.scene == scene and t.level == level]


def passes_over(step: Step, world: World) -> tuple[str, ...]:
    """The bodies the carried object is routed over: each 'via' body, and for 'avoid X' the
    other body on the way in X's column (the detour the words ask for)."""
    over = set()
    for mode, body in step.waypoints:
        if mode == "via":
            over.add(body)
            continue
        x = world.poses[body].x
        over.update(b for b in world.movable if b not in (body, step.source, step.target)
                    and abs(world.poses[b].x - x) <= COLUMN_TOLERANCE)
    return tuple(sorted(over))


def signature(behaviour: Behaviour, world: World) -> tuple:
    """What the repertoire compares: the steps performed, routes as the bodies passed over
    (not the words, not the branch)."""
    return tuple((s.arm, s.action, s.source, s.relation, s.target, passes_over(s, world),
                  s.yaw_degrees) for s in behaviour.steps)


def episode_seed(task_id: str, round_index: int, base: int) -> int:
    """The seed of a task's round: fixed by the task id, the round and the split's seed base."""
    offset = int(hashlib.sha256(task_id.encode()).hexdigest()[:8], 16) % 1000
    return base + 100 * round_index + offset


def off_route(step: Step, world: World) -> list[str]:
    """Waypoints that no longer lie between the source and the destination (in x)."""
    if not step.waypoints:
        return []
    x_source, x_target = world.poses[step.source].x, world.poses[step.target].x
    low, high = min(x_source, x_target) - ROUTE_CORRIDOR, max(x_source, x_target) + ROUTE_CORRIDOR
    return [body for _, body in step.waypoints if not low <= world.poses[body].x <= high]


class _Generator:
    def __init__(self, scene: Scene, training: dict[str, Behaviour]):
        self.scene = scene
        self.training = training
        self.repertoire = {signature(training[t.label], World(scene, t.layout))
                           for t in scene.tasks}
        self.tasks: list[TestTask] = []
        self.rejected: list[Rejection] = []
        self.seen: dict[tuple[str, str], str] = {}

    def reject(self, level: Level, layout: str, instruction: str, origin: str,
               reason: str) -> None:
        self.rejected.append(Rejection(scene=self.scene.id, level=level, layout=layout,
                                       instruction=instruction, origin=origin, reason=reason))

    def fill_arms(self, behaviour: Behaviour, origin: str) -> Behaviour:
        """Unnamed arms take the training task's arms (its paraphrases name them)."""
        arms = [s.arm for s in self.training[origin].steps]
        if len(arms) != len(behaviour.steps):
            return behaviour
        steps = tuple(s if s.arm else s.model_copy(update={"arm": a})
                      for s, a in zip(behaviour.steps, arms, strict=True))
        return behaviour.model_copy(update={"steps": steps})

    def consider(self, level: Level, layout: str, instruction: str, form: lf.Instruction,
                 origin: str, wording: str) -> None:
        key = (layout, instruction)
        if key in self.seen:
            self.reject(level, layout, instruction, origin, f"duplicate of {self.seen[key]}")
            return
        world = World(self.scene, layout)
        try:
            behaviour = self.fill_arms(ground(form, world), origin)
        except GroundingError as error:
            self.reject(level, layout, instruction, origin, f"{error.code}: {error.message}")
            return
        if signature(behaviour, world) not in self.repertoire:
            self.reject(level, layout, instruction, origin,
                        f"outside the training repertoire: {describe(behaviour)}")
            return
        stray = [b for step in behaviour.steps for b in off_route(step, world)]
        if stray:
            self.reject(level, layout, instruction, origin,
                        f"waypoint {', '.join(stray)} is no longer on the way")
            return
        suffix = "" if level == "L0" else f"@{layout}"
        task_id = f"{self.scene.id}/{level}/{origin}{suffix}"
        self.seen[key] = task_id
        self.tasks.append(TestTask(id=task_id, scene=self.scene.id, level=level, layout=layout,
                                   instruction=instruction, form=form, behaviour=behaviour,
                                   origin=origin, wording=wording))

    def level0(self) -> None:
        for task in self.scene.tasks:
            self.consider("L0", task.layout, task.paraphrases[0], task.forms[0], task.label,
                          "training")

    def level1(self) -> None:
        rule = self.scene.splits.get("L1")
        for layout in rule.layouts if rule else ():
            for task in self.scene.tasks:
                self.consider("L1", layout, task.paraphrases[0], task.forms[0], task.label,
                              "training")


def generate(spec: Spec, training: dict[str, Behaviour],
             levels: tuple[Literal["L0", "L1"], ...] = ("L0", "L1")) -> Splits:
    """Test tasks for the given levels of every scene, with every rejected candidate."""
    tasks: list[TestTask] = []
    rejected: list[Rejection] = []
    for scene in spec.scenes.values():
        generator = _Generator(scene, training)
        for level in levels:
            getattr(generator, f"level{level[1]}")()
        tasks += generator.tasks
        rejected += generator.rejected
    return Splits(tasks=tuple(tasks), rejected=tuple(rejected))
