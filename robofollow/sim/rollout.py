"""Running the scripted expert on one compiled episode, recording (and optionally rendering)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from robofollow.compiler.behaviour import Behaviour
from robofollow.compiler.plans import plan
from robofollow.compiler.spec import Scene
from robofollow.oracle.end_state import achieved
from robofollow.sim import robot
from robofollow.sim.cameras import Cameras, side_by_side
from robofollow.sim.expert import Expert
from robofollow.sim.recorder import Recorder
from robofollow.sim.simulation import Simulation
from robofollow.trajectory import Trajectory


@dataclass
class ExpertRun:
    episode: str
    achieved: bool
    reasons: list[str]
    steps: int
    seconds: float
    trajectory: Trajectory
    frames: list[np.ndarray] = field(default_factory=list)  # side-by-side camera rows

    def summary(self) -> dict:
        return {"episode": self.episode, "achieved": self.achieved, "reasons": self.reasons,
                "steps": self.steps, "seconds": round(self.seconds, 3)}


def run_expert(scene: Scene, episode: dict, render: bool = False, width: int = 320,
               height: int = 240) -> ExpertRun:
    """Reset to the episode's layout and seed, execute the expert's plan, check the end state."""
    began = time.perf_counter()
    sim = Simulation(scene, episode["layout"], width, height)
    world = sim.reset(episode["seed"])
    behaviour = Behaviour.model_validate(episode["behaviour"])
    actions = Expert(sim).actions(plan(behaviour, world))
    recorder = Recorder(sim, {key: episode[key] for key in ("episode", "scene", "layout", "seed")})
    cameras = Cameras(sim, width, height) if render else None
    frames = []

    def record(action: np.ndarray) -> None:
        recorder.frame(action)
        if cameras:
            frames.append(side_by_side(cameras.images()))

    try:
        record(robot.home_state())  # frame 0: the settled start, arms at home
        for action in actions:
            sim.step(action)
            record(action)
    finally:
        if cameras:
            cameras.close()
    trajectory = recorder.trajectory()
    ok, reasons = achieved(behaviour, trajectory, scene)
    return ExpertRun(episode["episode"], ok, reasons, len(actions),
                     time.perf_counter() - began, trajectory, frames)
