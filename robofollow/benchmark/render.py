"""A build's files as text (what `output.write` writes beside audit.json and summary.txt):
each scene's episodes and test tasks, the tasks with their goal DAGs and expert plans, and
the rejected candidates."""

from __future__ import annotations

from robofollow.benchmark.compiled import Compiled
from robofollow.benchmark.labels import labels
from robofollow.benchmark.output import REJECTED, episode_files
from robofollow.benchmark.rounds import episode_lines, ordered_tasks
from robofollow.compiler.planning.goals import goal_graph, graph_to_dict
from robofollow.compiler.planning.plans import plan
from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.compiler.scene.spec import LEVELS, Scene
from robofollow.compiler.scene.world import World
from robofollow.files import json_line


def _line(record: dict) -> str:
    return json_line(record, sort_keys=True)


def rendered(compiled: Compiled) -> dict[str, str]:
    """The build's files but audit.json and summary.txt, by path in the build folder:
    episodes/ and tasks/ of every scene and level, and rejected.jsonl. A scene's files depend
    on its own compile alone, and rejected.jsonl lists the scenes' rejections one after the
    other (see `output.joined`)."""
    return episode_files(compiled.spec.scenes, *episodes(compiled)) | task_files(compiled)


def episodes(compiled: Compiled) -> tuple[tuple[str, ...], tuple[bytes, ...]]:
    """A compile's episodes in scene, level and task order: their ids, and their records as
    the build writes them (JSON lines, without the newline)."""
    lines = [line for task in ordered_tasks(compiled) for line in episode_lines(compiled, task)]
    return (tuple(episode for episode, _ in lines),
            tuple(line.rstrip("\n").encode() for _, line in lines))


def task_files(compiled: Compiled) -> dict[str, str]:
    """The tasks/ files of every scene and level, and rejected.jsonl."""
    files = {}
    for scene in compiled.spec.scenes:
        goals_and_plans = _GoalsAndPlans(compiled.spec.scenes[scene])
        for level in LEVELS:
            files[f"tasks/{scene}_{level}.jsonl"] = "".join(
                _task_line(goals_and_plans, task, compiled.training)
                for task in compiled.splits.of(scene, level))
    return files | {REJECTED: "".join(_line(r.model_dump(mode="json"))
                                      for r in compiled.splits.rejected)}


def _task_line(goals_and_plans: _GoalsAndPlans, task, training) -> str:
    goal, points = goals_and_plans.of(task.behaviour, task.layout)
    return _line({"task": task.id, "origin": task.origin, "wording": task.wording,
                  "layout": task.layout, "instruction": task.instruction,
                  **labels(goals_and_plans.scene, task, training),
                  "goal": goal, "plan": points})


class _GoalsAndPlans:
    """A scene's goal DAGs and expert plans as the task files hold them, each made once (a
    reworded task asks for its origin's behaviour on its origin's layout)."""

    def __init__(self, scene: Scene):
        self.scene = scene
        self.worlds: dict[str, World] = {}
        self.made: dict[tuple[str, str], tuple[dict, list]] = {}

    def of(self, behaviour: Behaviour, layout: str) -> tuple[dict, list]:
        key = behaviour.model_dump_json(), layout
        if key not in self.made:
            if layout not in self.worlds:
                self.worlds[layout] = World(self.scene, layout)
            self.made[key] = (graph_to_dict(goal_graph(behaviour)),
                              plan(behaviour, self.worlds[layout]).model_dump(
                                  mode="json")["points"])
        return self.made[key]
