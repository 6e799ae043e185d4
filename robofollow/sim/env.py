"""A Gymnasium 1.x environment over the compiled benchmark's episodes.

    env = RoboFollowEnv()                       # the current release, every episode
    obs, info = env.reset(options={"episode": "scene2/L0/pickup_left_cube#r1"})
    env = gymnasium.make("RoboFollow-Scene2-v0", level="L1")   # see robofollow.sim.registration
    obs, reward, terminated, truncated, info = env.step(action)   # 14-D joint targets

Observation: {"images": {cam_high, cam_left_wrist, cam_right_wrist} (H, W, 3) uint8,
"state": 14-D joints (grippers normalised, 1 open), "instruction": the episode's text}, and
with `objects=True` "objects": the objects observation (sim/objects.py: every body's kind, size,
colour, position and yaw, ground truth, in an order that carries no identity).
`reset()` plays the env's `episode`, else one drawn (with the env's seeded generator) from
the episodes of `scene` and `level` (None: all). The episode fixes layout, instruction and
jitter seed; `reset(seed=...)` overrides the seed. The episodes come from a frozen release
(robofollow.release: the current one, or `release="v1"`), or with `specs=` from a working
compile of those specs (the on-disk compile cache).
Reward is always 0 and nothing terminates early: the oracle scores the recorded trajectory
(`env.trajectory()`), as the benchmark's protocol runs a fixed action budget. Targets past a
joint limit are clipped to it; `info["clipped"]` counts the actions that had one.
"""

from __future__ import annotations

import string
from pathlib import Path

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from robofollow import release as releases
from robofollow.benchmark.episode import Episode
from robofollow.sim import MAX_STEPS, robot
from robofollow.sim.cameras import CAMERA_NAMES, Cameras
from robofollow.sim.objects import SHAPE as OBJECTS_SHAPE
from robofollow.sim.objects import observe_objects
from robofollow.sim.recorder import Recorder
from robofollow.sim.simulation import CONTROL_HZ, Simulation
from robofollow.sim.stage import Stage
from robofollow.trajectory import Trajectory

INSTRUCTION_CHARSET = frozenset(string.printable) - frozenset("\t\n\r\x0b\x0c")


class RoboFollowEnv(gym.Env):
    metadata = {"render_modes": ["rgb_array"], "render_fps": CONTROL_HZ}

    def __init__(self, episode: str | Episode | None = None, specs: str | Path | None = None,
                 width: int = 320, height: int = 240, max_steps: int = MAX_STEPS,
                 render_mode: str | None = "rgb_array", scene: str | None = None,
                 level: str | None = None, objects: bool = False, release: str | None = None):
        self.benchmark = releases.benchmark(release, Path(specs) if specs else None)
        self.choices = self.benchmark.select(scene, level)  # what reset() draws from
        self.default_episode = self._episode(episode) if episode else None
        self.width, self.height, self.max_steps = width, height, max_steps
        self.render_mode, self.objects = render_mode, objects
        image = spaces.Box(0, 255, (height, width, 3), np.uint8)
        parts = {
            "images": spaces.Dict({name: image for name in CAMERA_NAMES}),
            "state": spaces.Box(robot.ACTION_LOW.astype(np.float32),
                                robot.ACTION_HIGH.astype(np.float32), dtype=np.float32),
            "instruction": spaces.Text(max_length=1000, min_length=0,
                                       charset=INSTRUCTION_CHARSET),
        }
        if objects:
            parts["objects"] = spaces.Box(-np.inf, np.inf, OBJECTS_SHAPE, np.float32)
        self.observation_space = spaces.Dict(parts)
        self.action_space = spaces.Box(robot.ACTION_LOW.astype(np.float32),
                                       robot.ACTION_HIGH.astype(np.float32), dtype=np.float32)
        self.stage = Stage(width, height)  # the current layout's simulation and cameras
        self.recorder: Recorder | None = None
        self.episode: Episode | None = self.default_episode
        self.steps = self.clipped = 0  # clipped: actions with a target past a joint limit
        self.command = robot.home_state()

    def _episode(self, episode: str | Episode) -> Episode:
        """An episode given by id, or a compiled episode."""
        return self.benchmark.record(episode) if isinstance(episode, str) else episode

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        episode = (options or {}).get("episode") or self.default_episode
        if episode is None:
            episode = self.choices[self.np_random.integers(len(self.choices))]
        self.episode = self._episode(episode)
        scene = self.benchmark.spec.scenes[self.episode.scene]
        self.stage.simulation(scene, self.episode.layout, render=True)
        jitter_seed = self.episode.seed if seed is None else seed
        self.sim.reset(jitter_seed)
        self.steps, self.clipped, self.command = 0, 0, robot.home_state()
        self.recorder = Recorder(self.sim, {**self.episode.meta(), "seed": jitter_seed})
        self.recorder.frame(self.command)
        return self._observation(), self._info()

    def step(self, action):
        if self.sim is None:
            raise RuntimeError("call reset() before step()")
        action = np.asarray(action, dtype=np.float64).reshape(-1)
        if action.shape != (14,) or not np.all(np.isfinite(action)):
            raise ValueError(f"an action is 14 finite joint targets, got shape {action.shape}")
        self.command, past = robot.clip_to_limits(action)
        self.clipped += int(past)
        self.sim.step(self.command)
        self.steps += 1
        self.recorder.frame(self.command)
        truncated = self.steps >= self.max_steps
        return self._observation(), 0.0, False, truncated, self._info()

    def _observation(self) -> dict:
        found = {"images": self.cameras.images(),
                 "state": robot.observed_state(self.sim.state()),
                 "instruction": self.episode.instruction}
        if self.objects:
            found["objects"] = observe_objects(self.sim)
        return found

    def _info(self) -> dict:
        return {"episode": self.episode.id, "scene": self.episode.scene,
                "level": self.episode.level, "layout": self.episode.layout,
                "seed": self.recorder.meta["seed"], "step": self.steps,
                "clipped": self.clipped}

    def trajectory(self) -> Trajectory:
        """The episode so far, one frame per control step (frame 0 = the settled start)."""
        return self.recorder.trajectory()

    def render(self):
        return self.cameras.render("cam_high") if self.cameras else None

    @property
    def sim(self) -> Simulation | None:
        return self.stage.sim

    @property
    def cameras(self) -> Cameras | None:
        return self.stage.cameras

    def close(self) -> None:
        self.stage.close()
