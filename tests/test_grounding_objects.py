"""`Grounder.objects`, the jitter check's quick grounding, agrees with `Grounder.behaviour`: the
same (source, target) per step, or the same error, for every shipped test task's form in the
jitter worlds of its own layout (where it grounds) and in the nominal worlds of its scene's
other layouts (where many do not)."""

from __future__ import annotations

from robofollow.compiler.scene.grounding import Grounder, GroundingError
from robofollow.compiler.scene.world import World, jitter_worlds
from tests.sim_helpers import benchmark


def _objects(grounder: Grounder, form) -> tuple:
    try:
        return "grounds", grounder.objects(form)
    except GroundingError as error:
        return "fails", error.code, error.message


def _behaviour(grounder: Grounder, form) -> tuple:
    try:
        return "grounds", tuple((s.source, s.target) for s in grounder.behaviour(form).steps)
    except GroundingError as error:
        return "fails", error.code, error.message


def test_objects_agree_with_behaviour():
    compiled = benchmark()
    worlds: dict[tuple[str, str], list[Grounder]] = {}
    outcomes = {"grounds": 0, "fails": 0}
    for task in compiled.splits.tasks:
        scene = compiled.spec.scenes[task.scene]
        if (task.scene, task.layout) not in worlds:
            worlds[task.scene, task.layout] = [Grounder(w) for w in
                                               jitter_worlds(scene, task.layout)]
        others = [Grounder(World(scene, layout)) for layout in scene.layouts
                  if layout != task.layout]
        for grounder in worlds[task.scene, task.layout] + others:
            quick = _objects(grounder, task.form)
            assert quick == _behaviour(grounder, task.form), (task.id, grounder.world.layout.name)
            outcomes[quick[0]] += 1
    assert outcomes["grounds"] > 10_000 and outcomes["fails"] > 300, outcomes  # (19,036 and 580)
