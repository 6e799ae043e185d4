"""The instruction a policy is given: the episode's own (normal), none (the paper's "empty
language" control) or another task's (shuffled: a training paraphrase of the scene whose steps
on this layout differ from the episode's, drawn with the episode's seed)."""

from __future__ import annotations

import numpy as np

from robofollow.benchmark.episode import Benchmark, Episode
from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.compiler.scene.grounding import ground
from robofollow.compiler.scene.world import World
from robofollow.errors import RoboFollowError
from robofollow.eval.running.modes import INSTRUCTION_MODES


def given_instruction(compiled: Benchmark, episode: Episode, mode: str) -> str:
    if mode == "normal":
        return episode.instruction
    if mode == "empty":
        return ""
    if mode == "shuffled":
        options = [text for text, behaviour in _groundings(compiled, episode.scene,
                                                           episode.layout)
                   if behaviour.steps != episode.behaviour.steps]
        if not options:
            raise RoboFollowError(f"{episode.id}: no other training instruction of "
                                  f"{episode.scene} grounds on layout {episode.layout}")
        return options[int(np.random.default_rng(episode.seed).integers(len(options)))]
    raise ValueError(f"instruction mode must be one of {INSTRUCTION_MODES}, got {mode!r}")


_GROUNDINGS: dict[tuple[str, str, str], tuple[tuple[str, Behaviour], ...]] = {}


def _groundings(compiled: Benchmark, scene_id: str, layout: str
                ) -> tuple[tuple[str, Behaviour], ...]:
    """Every training paraphrase of the scene that grounds on the layout (nominal poses), with
    the behaviour it asks for there; computed once per layout."""
    key = (compiled.spec.digest, scene_id, layout)
    if key not in _GROUNDINGS:
        _GROUNDINGS[key] = _ground_all(compiled, scene_id, layout)
    return _GROUNDINGS[key]


def _ground_all(compiled: Benchmark, scene_id: str, layout: str
                ) -> tuple[tuple[str, Behaviour], ...]:
    scene = compiled.spec.scenes[scene_id]
    world = World(scene, layout)
    found = []
    for task in scene.tasks:
        for text, form in zip(task.paraphrases, task.forms, strict=True):
            try:
                found.append((text, ground(form, world)))
            except RoboFollowError:
                continue
    return tuple(found)
