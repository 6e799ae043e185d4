"""Running the scripted expert on one compiled episode, recording (and optionally rendering),
and scoring the recording with the oracle."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from robofollow.compiler.behaviour import Behaviour
from robofollow.compiler.plans import plan
from robofollow.compiler.spec import Scene
from robofollow.oracle.results import EpisodeScore
from robofollow.oracle.score import score
from robofollow.sim import robot
from robofollow.sim.expert import Expert
from robofollow.sim.recorder import Recorder
from robofollow.sim.simulation import Simulation
from robofollow.sim.stage import Stage
from robofollow.trajectory import Trajectory

META_KEYS = ("episode", "scene", "layout", "seed")


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


OnImages = Callable[[dict[str, np.ndarray]], None]


def execute(sim: Simulation, actions, meta: dict, on_frame: Callable[[], None] | None = None
            ) -> Trajectory:
    """Record the settled start (arms at home), then step and record each action; `on_frame`
    is called after each recorded frame (e.g. to render it)."""
    recorder = Recorder(sim, meta)

    def record(action: np.ndarray) -> None:
        recorder.frame(action)
        if on_frame:
            on_frame()

    record(robot.home_state())
    for action in actions:
        sim.step(action)
        record(action)
    return recorder.trajectory()


class ExpertRunner(Stage):
    """Runs the expert on episodes, reusing the current layout's simulation and renderer."""

    def run(self, scene: Scene, episode: dict, on_images: OnImages | None = None) -> ExpertRun:
        """Reset to the episode's layout and seed, execute the expert's plan (handing each
        frame's camera images to `on_images`, if given), and score the recording."""
        began = time.perf_counter()
        sim = self.simulation(scene, episode["layout"], render=on_images is not None)
        world = sim.reset(episode["seed"])
        behaviour = Behaviour.model_validate(episode["behaviour"])
        actions = Expert(sim).actions(plan(behaviour, world))
        on_frame = (lambda: on_images(self.cameras.images())) if on_images else None
        trajectory = execute(sim, actions, {k: episode[k] for k in META_KEYS}, on_frame)
        result = score(behaviour, trajectory, scene, episode=episode["episode"])
        return ExpertRun(episode["episode"], result, len(actions), time.perf_counter() - began,
                         trajectory)


def run_expert(scene: Scene, episode: dict, on_images: OnImages | None = None,
               width: int = 320, height: int = 240) -> ExpertRun:
    """One expert episode in a fresh simulation (see ExpertRunner.run)."""
    with ExpertRunner(width, height) as runner:
        return runner.run(scene, episode, on_images)
