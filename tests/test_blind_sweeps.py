"""Language-blind motion primitives score at or below chance: a sweep along each row of
objects, the closed gripper at push height pushing everything in its way (each arm from its
own side), recorded once per layout and scored against every test task on that layout. In
every scene and level, each sweep's mean Intent over the tasks is at most the tasks' mean
chance level (a language-blind guess among the training behaviours)."""

from __future__ import annotations

from collections import defaultdict
from functools import cache

import numpy as np
import pytest

from robofollow.eval.running.chance import references
from robofollow.scoring import score_recording
from tests.judged import Script
from tests.sim_helpers import cached_benchmark

ROW = 0.03  # m: movable bodies this close in y stand in one row
BEYOND = 0.08  # m: a sweep starts and ends this far past the row's outer bodies


def rows(script: Script) -> list[tuple[float, float, float]]:
    """(y, leftmost x, rightmost x) of each row of movable bodies."""
    found: list[list[tuple[float, float]]] = []
    for body in sorted(script.world.movable, key=lambda b: script.at(b)[1]):
        x, y, _ = script.at(body)
        if found and abs(y - found[-1][-1][1]) <= ROW:
            found[-1].append((x, y))
        else:
            found.append([(x, y)])
    return [(float(np.mean([y for _, y in row])), min(x for x, _ in row),
             max(x for x, _ in row)) for row in found]


@cache
def cells() -> dict[tuple[str, str], dict[str, list[dict]]]:
    """Round-1 test episodes by scene x level, then by layout."""
    grouped: dict = defaultdict(lambda: defaultdict(list))
    for episode in cached_benchmark().episodes():
        if episode.round == 1:
            grouped[episode.scene, episode.level][episode.layout].append(episode)
    return grouped


@cache
def sweeps(episode_id: str) -> tuple:
    """Each sweep's recording in this episode's layout and seed: (name, trajectory)."""
    recorded = []
    for index, (y, left, right) in enumerate(rows(Script(episode_id, cached_benchmark()))):
        for arm, start, end in (("left", left - BEYOND, right + BEYOND),
                                ("right", right + BEYOND, left - BEYOND)):
            script = Script(episode_id, cached_benchmark()).sweep(arm, y, start, end)
            recorded.append((f"the {arm} arm along row {index + 1} from the front",
                             script.trajectory()))
    return tuple(recorded)


@pytest.mark.slow
@pytest.mark.parametrize("scene", ["scene1", "scene2", "scene3", "scene4"])
def test_sweeping_blindly_scores_at_or_below_chance_in_every_level(scene):
    compiled = cached_benchmark()  # the working compile: a property of the generated tests
    for level in ("L0", "L1", "L2", "L3"):
        layouts = cells()[scene, level]
        episodes = [e for group in layouts.values() for e in group]
        chance = np.mean([references(compiled, e, e.instruction)["chance"]["IS"]
                          for e in episodes])
        earned: dict[str, list[float]] = defaultdict(list)
        for group in layouts.values():
            for name, trajectory in sweeps(group[0].id):
                for episode in group:
                    result = score_recording(compiled, episode, trajectory)
                    earned[name].append(result.intent_score)
        for name, scores in earned.items():
            assert len(scores) == len(episodes)
            assert np.mean(scores) <= chance + 1e-9, (scene, level, name, np.mean(scores),
                                                      chance)
