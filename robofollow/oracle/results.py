"""Typed scoring results: one record per stage, one per episode."""

from __future__ import annotations

from robofollow.compiler.scene.model import Model


class StageResult(Model):
    stage: str  # the goal-DAG node, e.g. "source", "objective", "step2.source", "finish"
    name: str  # what the stage checks, e.g. "source_grounding", "route", "finish"
    weight: float
    intent: float  # credit earned, 0 or the weight
    execution: float
    first_step: int | None  # frame where the stage's intent was first met (or that decided it)
    reason: str


class ExecutedBehaviour(Model):
    """What the trajectory shows the arms did, and the closest known behaviour."""

    description: str
    match: str | None  # "instructed", "other branch", a training task's label, or None
    behaviour: str | None  # the match's steps, in the specs' `expect` syntax
    intent_score: float  # the trajectory's scores against the match
    execution_score: float
    arms_moved: bool | None = None  # a gripper left its start (None: not recorded)


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

    def table(self) -> str:
        """The stage table, the totals and what the arms did, for people."""
        lines = [f"{'stage':<16}{'weight':>7}{'intent':>8}{'exec':>6}{'frame':>7}  reason"]
        for s in self.stages:
            frame = "-" if s.first_step is None else str(s.first_step)
            lines.append(f"{s.stage:<16}{s.weight:>7.2f}{s.intent:>8.2f}{s.execution:>6.2f}"
                         f"{frame:>7}  {s.reason}")
        weight = sum(s.weight for s in self.stages)
        lines.append(f"{'total':<16}{weight:>7.2f}{self.intent_score:>8.2f}"
                     f"{self.execution_score:>6.2f}   complete: {'yes' if self.complete else 'no'}")
        if self.other_branch:
            lines.append("the branch the condition does not select was carried out")
        did = self.executed_behaviour
        if did is not None:
            lines.append(f"did: {did.description}")
            if did.match is not None:
                lines.append(f"closest behaviour: {did.match} ({did.behaviour}; Intent "
                             f"{did.intent_score:.2f}, Execution {did.execution_score:.2f})")
        lines.append(f"profile: {self.profile.get('name', '?')}")
        return "\n".join(lines)
