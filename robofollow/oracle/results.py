"""Typed scoring results: one record per stage, one per episode."""

from __future__ import annotations

from robofollow.compiler.model import Model


class StageResult(Model):
    stage: str  # the goal-DAG node, e.g. "source", "objective", "step2.source", "finish"
    name: str  # what the stage checks, e.g. "source_grounding", "route", "finish"
    weight: float
    intent: float  # credit earned, 0 or the weight
    execution: float
    first_step: int | None  # frame where the stage's intent was first met
    reason: str


class ExecutedBehaviour(Model):
    """What the trajectory shows the arms did, and the closest known behaviour."""

    description: str
    match: str | None  # "instructed", "other branch", a training task's label, or None
    behaviour: str | None  # the match's steps, in the specs' `expect` syntax
    intent_score: float  # the trajectory's scores against the match
    execution_score: float


class EpisodeScore(Model):
    episode: str | None
    intent_score: float
    execution_score: float
    complete: bool
    stages: tuple[StageResult, ...]
    executed_behaviour: ExecutedBehaviour | None
    other_branch: bool | None  # a conditional: whether the branch not selected was started
    profile: dict  # the scoring profile in force

    @property
    def failures(self) -> list[str]:
        """One line per stage that did not earn full credit."""
        return [f"{s.stage}: {s.reason}" for s in self.stages
                if s.intent < s.weight or s.execution < s.weight]
