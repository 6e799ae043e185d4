"""The records a split generator makes: a test task, a rejected candidate, the splits of a
compile, and the seed of a task's round."""

from __future__ import annotations

import hashlib
from typing import Literal

from robofollow.compiler.language import lf
from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.compiler.scene.model import Model
from robofollow.compiler.scene.spec import Level


class TestTask(Model):
    id: str
    scene: str
    level: Level
    layout: str
    instruction: str
    form: lf.Instruction
    behaviour: Behaviour
    origin: str  # the training task it derives from
    wording: str  # "training", "listed", or the generator that reworded it
    # L1 / L3: whether the expert's motion differs from the origin training task's
    motion: Literal["moved", "as-trained"] | None = None


class Rejection(Model):
    scene: str
    level: Level
    layout: str
    instruction: str
    origin: str
    reason: str


class Splits(Model):
    tasks: tuple[TestTask, ...]
    rejected: tuple[Rejection, ...]

    def of(self, scene: str, level: Level) -> list[TestTask]:
        return [t for t in self.tasks if t.scene == scene and t.level == level]


def episode_seed(task_id: str, round_index: int, base: int) -> int:
    """The seed of a task's round: fixed by the task id, the round and the split's seed base."""
    offset = int(hashlib.sha256(task_id.encode()).hexdigest()[:8], 16) % 1000
    return base + 100 * round_index + offset
