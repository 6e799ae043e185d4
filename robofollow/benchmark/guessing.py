"""What a language-blind policy can earn in each test cell at best: on each layout of the cell,
the one training behaviour the layout allows that earns the most over the cell's tasks there
(chosen knowing them), performed perfectly. Beside the chance level (a uniform guess), it says
how much of a cell the instruction decides: where it is high, a policy that ignores the words
but happens to do the right thing on each layout scores well, and the cell tells following
from guessing apart poorly."""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterable, Mapping

from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.compiler.scene.spec import LEVELS, Spec, scene_behaviours
from robofollow.compiler.scene.world import World
from robofollow.compiler.splits.generator import TestTask
from robofollow.oracle.chance import available_behaviours, best_guess


def blind_best(spec: Spec, training: Mapping[str, Behaviour],
               tasks: Iterable[TestTask]) -> dict[str, dict[str, dict[str, float]]]:
    """{scene: {level: {"IS": 0-100, "CR": 0-100}}}: the best language-blind guess's mean
    Intent and completion rate over the cell's test tasks (cells without tasks are left out)."""
    cells: dict[tuple[str, str], dict[str, list[Behaviour]]] = defaultdict(
        lambda: defaultdict(list))
    for task in tasks:
        cells[task.scene, task.level][task.layout].append(task.behaviour)
    found: dict[str, dict[str, dict[str, float]]] = {}
    for scene_id, scene in spec.scenes.items():
        candidates = scene_behaviours(spec, training, scene_id)
        for level in LEVELS:
            layouts = cells.get((scene_id, level))
            if not layouts:
                continue
            earned = {"IS": 0.0, "CR": 0.0}
            for layout, asked in layouts.items():
                labels = available_behaviours(World(scene, layout), candidates)
                best = best_guess(asked, [candidates[label] for label in labels])
                earned = {metric: earned[metric] + best[metric] for metric in earned}
            count = sum(len(asked) for asked in layouts.values())
            found.setdefault(scene_id, {})[level] = {
                metric: round(100 * value / count, 1) for metric, value in earned.items()}
    return found
