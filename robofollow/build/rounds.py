"""A compiled test task's episodes: one per round of its level's split rule, each with its own
seed; every episode of a build; finding one by id."""

from __future__ import annotations

import difflib
import hashlib

from robofollow.build.episode import Episode
from robofollow.build.pipeline import Compiled
from robofollow.compiler.spec import LEVELS, SplitRule
from robofollow.compiler.splits import TestTask, episode_seed
from robofollow.errors import RoboFollowError
from robofollow.files import json_line


def episodes(compiled: Compiled, task: TestTask) -> list[Episode]:
    """The task's episodes, one per round of its level's split rule."""
    rule = compiled.spec.scenes[task.scene].splits.get(task.level) or SplitRule(level=task.level)
    records = []
    for round_index in range(1, rule.rounds + 1):
        fields = {"episode": f"{task.id}#r{round_index}", "task": task.id, "scene": task.scene,
                  "level": task.level, "layout": task.layout, "instruction": task.instruction,
                  "lf": task.form, "behaviour": task.behaviour, "round": round_index,
                  "seed": episode_seed(task.id, round_index, rule.seed)}
        unhashed = Episode(**fields, hash="")
        content = compiled.spec.digest + json_line(
            unhashed.model_dump(mode="json", exclude={"hash"}), sort_keys=True)
        digest = hashlib.sha256(content.encode()).hexdigest()[:16]
        records.append(unhashed.model_copy(update={"hash": digest}))
    return records


def all_episodes(compiled: Compiled) -> list[Episode]:
    """Every episode of every level, in scene, level and task order."""
    return [episode for scene in compiled.spec.scenes for level in LEVELS
            for task in compiled.splits.of(scene, level) for episode in episodes(compiled, task)]


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
    return UnknownEpisodeError(f"no episode {episode_id!r} in the compiled benchmark (ids look "
                               f"like scene1/L0/pickup_yellow_block_2#r1){hint}")
