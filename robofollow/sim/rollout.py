"""Running episodes in simulation. A `Rollout` resets the episode's layout with its seed,
records the settled start (arms at home), steps and records actions within a budget, and
scores the recording through `scoring.score_recording` (the one door into the oracle, with
the scene's training behaviours as 'did instead' candidates). The expert here, the evaluation
harness, dataset generation and the vla-eval adapter all run episodes through it."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from robofollow.benchmark.episode import Benchmark, EpisodeSetup
from robofollow.compiler.planning.plans import plan
from robofollow.oracle.results import EpisodeScore
from robofollow.scoring import score_recording
from robofollow.sim import robot
from robofollow.sim.cameras import IMAGE_HEIGHT, IMAGE_WIDTH
from robofollow.sim.expert import Expert
from robofollow.sim.recorder import Recorder
from robofollow.sim.stage import Stage
from robofollow.trajectory import Trajectory

OnFrame = Callable[[Stage], None]
OnImages = Callable[[dict[str, np.ndarray]], None]


class Rollout:
    """An episode in progress: its layout reset with its seed, the recording from the home
    pose, and the actions executed so far (`done` once `budget` control steps are spent; None:
    no budget). `on_frame(stage)` is called after every recorded frame (e.g. to render it)."""

    def __init__(self, compiled: Benchmark, stage: Stage, episode: EpisodeSetup, render: bool,
                 budget: int | None = None, on_frame: OnFrame | None = None):
        self.compiled, self.stage, self.episode = compiled, stage, episode
        self.budget, self.on_frame = budget, on_frame
        self.scene = compiled.spec.scenes[episode.scene]
        self.sim = stage.simulation(self.scene, episode.layout, render=render)
        self.world = self.sim.reset(episode.seed)
        self.recorder = Recorder(self.sim, episode.meta())
        self.steps = 0
        self._record(robot.home_state())

    @property
    def done(self) -> bool:
        return self.budget is not None and self.steps >= self.budget

    def _record(self, action: np.ndarray) -> None:
        self.recorder.frame(action)
        if self.on_frame is not None:
            self.on_frame(self.stage)

    def execute(self, actions) -> int:
        """Step and record the actions, as many as the budget leaves; how many ran."""
        left = len(actions) if self.budget is None else min(len(actions),
                                                             self.budget - self.steps)
        for action in actions[:left]:
            self.sim.step(action)
            self._record(action)
            self.steps += 1
        return left

    def finish(self) -> tuple[EpisodeScore, Trajectory]:
        """The recording, scored by the oracle."""
        trajectory = self.recorder.trajectory()
        return score_recording(self.compiled, self.episode, trajectory), trajectory


@dataclass
class ExpertRun:
    episode: str
    score: EpisodeScore
    steps: int
    seconds: float
    trajectory: Trajectory

    @property
    def achieved(self) -> bool:
        """The oracle scores the episode complete."""
        return self.score.complete

    def summary(self) -> dict:
        return {"episode": self.episode, "achieved": self.achieved,
                "intent_score": self.score.intent_score,
                "execution_score": self.score.execution_score,
                "reasons": self.score.failures, "steps": self.steps,
                "seconds": round(self.seconds, 3)}


class ExpertRunner(Stage):
    """Runs the expert on episodes, reusing the current layout's simulation and renderer."""

    def run(self, compiled: Benchmark, episode: EpisodeSetup,
            on_images: OnImages | None = None) -> ExpertRun:
        """Reset to the episode's layout and seed, execute the expert's plan (handing each
        frame's camera images to `on_images`, if given), and score the recording."""
        began = time.perf_counter()
        on_frame = (lambda stage: on_images(stage.cameras.images())) if on_images else None
        rollout = Rollout(compiled, self, episode, on_images is not None, on_frame=on_frame)
        actions = Expert(rollout.sim).actions(plan(episode.behaviour, rollout.world))
        rollout.execute(actions)
        result, trajectory = rollout.finish()
        return ExpertRun(episode.id, result, len(actions), time.perf_counter() - began,
                         trajectory)


def run_expert(compiled: Benchmark, episode: EpisodeSetup, on_images: OnImages | None = None,
               width: int = IMAGE_WIDTH, height: int = IMAGE_HEIGHT) -> ExpertRun:
    """One expert episode in a fresh simulation (see ExpertRunner.run)."""
    with ExpertRunner(width, height) as runner:
        return runner.run(compiled, episode, on_images)
