"""Scene entropy H(T|S): how much the instruction, not the scene, decides the task.

Training tasks are grouped by their task-independent initial scene as a policy sees it: the
same scene family, layouts that look the same (observation.py: identical-looking bodies may
trade places) and the same jitter; not language or goals. With n demonstrations per task,
P(s) = n K_s / (n K) and, within a group, tasks are equally likely:

    H(T|S) = sum_s (K_s / K) log2 K_s

The paper counts task labels (K_s tasks in group s). Labels whose behaviours are the same
motions (motions.py) ask a policy for the same thing in different words. Over distinct
behaviours, with behaviour b taking n_b of its group's K_s labels (and their demonstrations),

    H(B|S) = sum_s (K_s / K) sum_b -(n_b / K_s) log2 (n_b / K_s)

which is what the scene leaves for language to decide; H(B|S) = H(T|S) when no two labels
of a group share a behaviour.
"""

from __future__ import annotations

import math

from robofollow.compiler.planning.motions import differences, motion
from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.compiler.scene.observation import same_observation
from robofollow.compiler.scene.spec import Spec
from robofollow.compiler.scene.world import World


def _jitter(spec: Spec, scene_id: str, layout: str) -> list:
    scene = spec.scenes[scene_id]
    return sorted(scene.jitter_of(b).model_dump_json() for b in scene.layouts[layout].placed)


def scene_groups(spec: Spec) -> list[dict]:
    """Training tasks grouped by initial scene: [{"layout": "scene/layout", "tasks": [...]}]
    (the layout named is the group's first)."""
    groups: list[dict] = []
    for task in spec.tasks:
        scene = spec.scenes[task.scene]
        group = next((g for g in groups if g["scene"] == task.scene
                      and same_observation(scene, g["first"], task.layout)
                      and _jitter(spec, task.scene, g["first"]) ==
                      _jitter(spec, task.scene, task.layout)), None)
        if group is None:
            group = {"scene": task.scene, "first": task.layout, "tasks": []}
            groups.append(group)
        group["tasks"].append(task.label)
    return [{"layout": f"{g['scene']}/{g['first']}", "tasks": g["tasks"]} for g in groups]


def same_behaviours(spec: Spec, training: dict[str, Behaviour], tasks: list[str]) -> list[list]:
    """Tasks of one group partitioned by behaviour: labels whose steps are the same motions."""
    by_label = {t.label: t for t in spec.tasks}
    classes: list[tuple[tuple, list[str]]] = []
    for label in tasks:
        task = by_label[label]
        world = World(spec.scenes[task.scene], task.layout)
        motions = tuple(motion(s, world) for s in training[label].steps)
        match = next((c for c in classes if len(c[0]) == len(motions) and all(
            not differences(a, b) for a, b in zip(c[0], motions, strict=True))), None)
        if match is None:
            classes.append((motions, [label]))
        else:
            match[1].append(label)
    return [labels for _, labels in classes]


def entropy_bits(group_sizes: list[int]) -> float:
    """H(T|S) for groups of K_s equally likely tasks with equal demonstration counts."""
    total = sum(group_sizes)
    return sum(k / total * math.log2(k) for k in group_sizes if k) if total else 0.0


def behaviour_entropy_bits(groups: list[list[int]]) -> float:
    """H(B|S) from each group's behaviour class sizes (labels per distinct behaviour)."""
    total = sum(sum(sizes) for sizes in groups)
    return sum(-n / total * math.log2(n / sum(sizes)) for sizes in groups for n in sizes
               if n) if total else 0.0


def scene_entropy(spec: Spec) -> float:
    return entropy_bits([len(g["tasks"]) for g in scene_groups(spec)])
