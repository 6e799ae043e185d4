"""A compiled test task's episodes: one per round of its level's split rule, each with its own
seed; every episode of a build; finding one by id."""

from __future__ import annotations

import difflib
from collections.abc import Iterator

from robofollow.benchmark.compiled import Compiled
from robofollow.benchmark.episode import Episode
from robofollow.benchmark.episode_hash import episode_hash, world_digest
from robofollow.compiler.scene.spec import LEVELS, SplitRule
from robofollow.compiler.splits.tasks import TestTask, episode_seed
from robofollow.errors import RoboFollowError
from robofollow.files import json_line_of, json_value


def _first(compiled: Compiled, task: TestTask) -> Episode:
    """The task's first episode, its hash left empty."""
    return Episode(id=f"{task.id}#r1", task=task.id, scene=task.scene, level=task.level,
                   layout=task.layout, instruction=task.instruction, lf=task.form,
                   behaviour=task.behaviour, round=1, seed=0, motion=task.motion, hash="",
                   split=compiled.split_digests[task.scene][:16])


def _rounds(compiled: Compiled, task: TestTask, first: Episode) -> Iterator[tuple[dict, str]]:
    """Each round of the task's level's split rule: the episode's record and its JSON line,
    as the build writes them (the hash covers what decides the episode alone,
    benchmark.episode_hash, so an episode keeps its hash while other tasks and layouts of its
    scene change). The values the rounds share are encoded once."""
    scene = compiled.spec.scenes[task.scene]
    rule = scene.splits.get(task.level) or SplitRule(level=task.level)
    world = world_digest(scene, task.layout)
    common = first.model_dump(mode="json", exclude={"hash", "split"})  # (rounds differ in 3)
    encoded = {key: json_value(value) for key, value in common.items()}
    for round_index in range(1, rule.rounds + 1):
        varying = {"episode": f"{task.id}#r{round_index}", "round": round_index,
                   "seed": episode_seed(task.id, round_index, rule.seed)}
        varying_encoded = {key: json_value(value) for key, value in varying.items()}
        varying["hash"] = episode_hash(world, {**encoded, **varying_encoded})
        varying["split"] = first.split
        record = {**common, **varying}
        yield record, json_line_of({**encoded, **varying_encoded,
                                    "hash": json_value(varying["hash"]),
                                    "split": json_value(first.split)})


def episodes(compiled: Compiled, task: TestTask) -> list[Episode]:
    """The task's episodes, one per round."""
    first = _first(compiled, task)
    return [first.model_copy(update={"id": record["episode"], "round": record["round"],
                                     "seed": record["seed"], "hash": record["hash"]})
            for record, _ in _rounds(compiled, task, first)]


def episode_records(compiled: Compiled, task: TestTask) -> list[dict]:
    """The task's episodes as JSON records, as the build writes them."""
    return [record for record, _ in _rounds(compiled, task, _first(compiled, task))]


def episode_lines(compiled: Compiled, task: TestTask) -> list[tuple[str, str]]:
    """The task's episodes as the build writes them: (episode id, JSON line)."""
    return [(record["episode"], line)
            for record, line in _rounds(compiled, task, _first(compiled, task))]


def ordered_tasks(compiled: Compiled) -> Iterator[TestTask]:
    """Every test task, in scene, level and task order."""
    for scene in compiled.spec.scenes:
        for level in LEVELS:
            yield from compiled.splits.of(scene, level)


def all_episodes(compiled: Compiled) -> list[Episode]:
    """Every episode of every level, in scene, level and task order."""
    return [episode for task in ordered_tasks(compiled) for episode in episodes(compiled, task)]


class UnknownEpisodeError(RoboFollowError):
    """An episode id that the compiled benchmark does not have."""


def find_episode(compiled: Compiled, episode_id: str) -> Episode:
    """The episode with this id (`<scene>/<level>/<task>#r<round>`)."""
    task_id, _, _ = episode_id.partition("#")
    for task in compiled.splits.tasks:
        if task.id == task_id:
            for episode in episodes(compiled, task):
                if episode.id == episode_id:
                    return episode
    raise unknown_episode(episode_id, [t.id for t in compiled.splits.tasks])


def unknown_episode(episode_id: str, task_ids: list[str]) -> UnknownEpisodeError:
    """The error for an episode id the benchmark lacks, with the nearest task ids."""
    close = difflib.get_close_matches(episode_id.partition("#")[0], task_ids, n=3)
    hint = f"; did you mean {', '.join(c + '#r1' for c in close)}?" if close else ""
    like = f"ids look like {task_ids[0]}#r1" if task_ids else "it has no test tasks"
    return UnknownEpisodeError(f"no episode {episode_id!r} in the compiled benchmark "
                               f"({like}){hint}")
