"""Running the scripted expert on one compiled episode, recording (and optionally rendering),
and scoring the recording with the oracle."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from robofollow.compiler.behaviour import Behaviour
from robofollow.compiler.plans import plan
from robofollow.compiler.spec import Scene
from robofollow.oracle.results import EpisodeScore
from robofollow.oracle.score import score
from robofollow.sim import robot
from robofollow.sim.cameras import Cameras, side_by_side
from robofollow.sim.expert import Expert
from robofollow.sim.recorder import Recorder
from robofollow.sim.simulation import Simulation
from robofollow.trajectory import Trajectory

META_KEYS = ("episode", "scene", "layout", "seed")


@dataclass
class ExpertRun:
    episode: str
    score: EpisodeScore
    steps: int
    seconds: float
    trajectory: Trajectory
    frames: list[np.ndarray] = field(default_factory=list)  # side-by-side camera rows

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


def execute(sim: Simulation, actions, meta: dict,
            cameras: Cameras | None = None) -> tuple[Trajectory, list[np.ndarray]]:
    """Record the settled start (arms at home), then step and record each action."""
    recorder, frames = Recorder(sim, meta), []

    def record(action: np.ndarray) -> None:
        recorder.frame(action)
        if cameras:
            frames.append(side_by_side(cameras.images()))

    record(robot.home_state())
    for action in actions:
        sim.step(action)
        record(action)
    return recorder.trajectory(), frames


def run_expert(scene: Scene, episode: dict, render: bool = False, width: int = 320,
               height: int = 240) -> ExpertRun:
    """Reset to the episode's layout and seed, execute the expert's plan, score it."""
    began = time.perf_counter()
    sim = Simulation(scene, episode["layout"], width, height)
    world = sim.reset(episode["seed"])
    behaviour = Behaviour.model_validate(episode["behaviour"])
    actions = Expert(sim).actions(plan(behaviour, world))
    cameras = Cameras(sim, width, height) if render else None
    try:
        trajectory, frames = execute(sim, actions, {k: episode[k] for k in META_KEYS}, cameras)
    finally:
        if cameras:
            cameras.close()
    result = score(behaviour, trajectory, scene, episode=episode["episode"])
    return ExpertRun(episode["episode"], result, len(actions), time.perf_counter() - began,
                     trajectory, frames)
