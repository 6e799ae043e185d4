"""Check training tasks against their layouts: one behaviour per task, as `expect` says, with
its route on the way (routes.py), that the expert can perform (feasibility.py).

Every paraphrase of a task must ground to the same behaviour. Paraphrases may leave the arm
unnamed ("Move the blue slab ..."); the task's arm is the one the others name, and naming two
arms is a disagreement.
"""

from __future__ import annotations

from robofollow.compiler.authoring.spec_files import Sources, spec_error
from robofollow.compiler.planning.feasibility import infeasible
from robofollow.compiler.planning.routes import degenerate_routes
from robofollow.compiler.scene.behaviour import Behaviour, describe
from robofollow.compiler.scene.grounding import GroundingError, ground
from robofollow.compiler.scene.spec import Expected, Scene, Spec, Task
from robofollow.compiler.scene.world import World
from robofollow.errors import SpecError, SpecErrors


class TaskProblem(Exception):
    """A training task whose paraphrase (by index) fails to ground or disagrees."""

    def __init__(self, code: str, message: str, index: int):
        super().__init__(message)
        self.code = code
        self.message = message
        self.index = index


def expected_behaviour(expected: Expected) -> Behaviour:
    return Behaviour(steps=expected.steps, branch=expected.branch)


def _without_arms(behaviour: Behaviour) -> Behaviour:
    steps = tuple(s.model_copy(update={"arm": None}) for s in behaviour.steps)
    return behaviour.model_copy(update={"steps": steps, "other": None, "condition": None})


def task_behaviour(task: Task, scene: Scene) -> Behaviour:
    """The behaviour a training task asks for on its layout; raises TaskProblem."""
    world = World(scene, task.layout)
    grounded = []
    for index, form in enumerate(task.forms):
        try:
            grounded.append(ground(form, world))
        except GroundingError as error:
            raise TaskProblem(error.code, error.message, index) from None
    first = grounded[0]
    arms: list[str | None] = [None] * len(first.steps)
    for index, behaviour in enumerate(grounded):
        if _without_arms(behaviour) != _without_arms(first):
            raise TaskProblem("paraphrases-disagree", f"paraphrase {index + 1} means "
                              f"{describe(behaviour)}, the first means {describe(first)}", index)
        for step_index, step in enumerate(behaviour.steps):
            if step.arm is not None and arms[step_index] not in (None, step.arm):
                raise TaskProblem("paraphrases-disagree", f"paraphrase {index + 1} names the "
                                  f"{step.arm} arm, an earlier one the {arms[step_index]} arm",
                                  index)
            arms[step_index] = arms[step_index] or step.arm
    if None in arms:
        raise TaskProblem("no-arm", "no paraphrase says which arm to use", 0)
    steps = tuple(s.model_copy(update={"arm": arm})
                  for s, arm in zip(first.steps, arms, strict=True))
    return first.model_copy(update={"steps": steps})


def training_behaviours(spec: Spec, sources: Sources, skip: dict[str, set[str]] | None = None
                        ) -> tuple[dict[str, Behaviour], list[SpecError]]:
    """Every training task's behaviour by label, and a located error (showing its line of
    `sources`) for each task that fails; tasks on the layouts in `skip` (scene -> layouts) are
    left unchecked."""
    behaviours: dict[str, Behaviour] = {}
    errors: list[SpecError] = []
    for scene in spec.scenes.values():
        for task in scene.tasks:
            if task.layout in (skip or {}).get(scene.id, ()):
                continue
            try:
                behaviour = task_behaviour(task, scene)
            except TaskProblem as problem:
                where = task.paraphrase_sources[problem.index]
                errors.append(spec_error(problem.code, problem.message, where, sources,
                                         len(task.paraphrases[problem.index]) + 2))
                continue
            if task.expect is not None:
                expected = expected_behaviour(task.expect)
                if (expected.branch, expected.steps) != (behaviour.branch, behaviour.steps):
                    errors.append(spec_error(
                        "expect-mismatch", f"the instructions mean {describe(behaviour)}, but "
                        f"expect says {describe(expected)}", task.source, sources,
                        len(task.label)))
                    continue
            world = World(scene, task.layout)
            routes = [p for step in behaviour.steps for p in degenerate_routes(step, world)]
            if routes:
                errors.append(spec_error("degenerate-route", "; ".join(routes), task.source,
                                         sources, len(task.label)))
                continue
            problems = infeasible(behaviour, world)
            if problems:
                errors.append(spec_error("infeasible", "the expert cannot do this: "
                                         + "; ".join(problems), task.source, sources,
                                         len(task.label)))
                continue
            behaviours[task.label] = behaviour
    return behaviours, errors


def check_training(spec: Spec) -> dict[str, Behaviour]:
    """Every training task's behaviour by label; SpecErrors lists every task that fails (with
    its line read from the spec file)."""
    behaviours, errors = training_behaviours(spec, Sources())
    if errors:
        raise SpecErrors(errors)
    return behaviours
