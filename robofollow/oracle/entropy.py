"""Scene entropy H(T|S): how much the instruction, not the scene, decides the task.

Training tasks are grouped by their task-independent initial scene: the bodies and their
attributes, where the layout puts them, and the jitter they get; not language or goals. With
n demonstrations per task, P(s) = n K_s / (n K) and, within a group, tasks are equally likely:

    H(T|S) = sum_s (K_s / K) log2 K_s
"""

from __future__ import annotations

import hashlib
import json
import math

from robofollow.compiler.spec import Spec


def initial_scene_key(spec: Spec, scene_id: str, layout: str) -> str:
    """A digest of everything a policy could see before the instruction arrives."""
    scene = spec.scenes[scene_id]
    placed = scene.layouts[layout].placed
    content = {
        "table": scene.table_height,
        "bodies": {b: scene.bodies[b].model_dump(mode="json") for b in sorted(placed)},
        "placed": {b: placed[b].model_dump(mode="json") for b in sorted(placed)},
        "jitter": {b: scene.jitter_of(b).model_dump(mode="json") for b in sorted(placed)},
    }
    return hashlib.sha256(json.dumps(content, sort_keys=True).encode()).hexdigest()


def scene_groups(spec: Spec) -> list[dict]:
    """Training tasks grouped by initial scene: [{"layout": "scene/layout", "tasks": [...]}]."""
    groups: dict[str, dict] = {}
    for task in spec.tasks:
        key = initial_scene_key(spec, task.scene, task.layout)
        group = groups.setdefault(key, {"layout": f"{task.scene}/{task.layout}", "tasks": []})
        group["tasks"].append(task.label)
    return list(groups.values())


def entropy_bits(group_sizes: list[int]) -> float:
    """H(T|S) for groups of K_s equally likely tasks with equal demonstration counts."""
    total = sum(group_sizes)
    return sum(k / total * math.log2(k) for k in group_sizes if k) if total else 0.0


def scene_entropy(spec: Spec) -> float:
    return entropy_bits([len(g["tasks"]) for g in scene_groups(spec)])
