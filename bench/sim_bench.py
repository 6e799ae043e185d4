"""Simulation throughput: raw physics, the env with three cameras, and the env's overhead.

    python bench/sim_bench.py [--runs 5] [--steps 150] [--scene scene4 --layout scene4_1]

Reports medians over runs of:
  - raw physics steps/s of the scene (mj_step, arms holding position);
  - env control steps/s with cam_high + both wrist cameras at 320x240, one process
    (target >= 50), and the summed rate of 2 processes running at once;
  - the env's cost as a ratio to bare MuJoCo doing the same work in the same run: the same
    physics steps plus rendering the same three frames with a bare mujoco.Renderer
    (target <= 1.15).
The episode is the current release's first in the layout, as the env reads it.
"""

from __future__ import annotations

import robofollow  # noqa: F401  (first: it sets MUJOCO_GL before mujoco loads)

# isort: split
import argparse
import multiprocessing
import statistics
import time

import mujoco
import numpy as np

from robofollow import release
from robofollow.benchmark.episode import Episode
from robofollow.cli.common import positive, scene_layout
from robofollow.errors import RoboFollowError
from robofollow.sim import robot
from robofollow.sim.cameras import CAMERA_NAMES
from robofollow.sim.env import RoboFollowEnv
from robofollow.sim.simulation import SUBSTEPS, Simulation


def _episode_of(scene: str, layout: str) -> Episode:
    """The first episode of the current release (what the env reads) in this layout."""
    benchmark = release.benchmark()
    found = next((e for e in benchmark.episodes(lambda i: i.startswith(f"{scene}/"))
                  if e.layout == layout), None)
    if found is None:
        raise RoboFollowError(f"release {benchmark.release} has no episode in {scene}/{layout}")
    return found


def raw_physics(scene: str, layout: str, steps: int) -> float:
    sim = Simulation(release.benchmark().spec.scenes[scene], layout)
    sim.reset(0)
    sim.apply(robot.home_state())
    began = time.perf_counter()
    mujoco.mj_step(sim.model, sim.data, nstep=steps)
    return steps / (time.perf_counter() - began)


def _actions(steps: int) -> np.ndarray:
    """A gentle joint-space sweep, so the arms move and the images change."""
    home = robot.home_state()
    phase = np.sin(np.linspace(0, 2 * np.pi, steps))[:, None]
    sweep = np.zeros(14)
    sweep[[0, 1, 7, 8]] = (0.4, 0.3, -0.4, 0.3)
    return home + phase * sweep


def env_loop(episode: Episode, steps: int) -> tuple[float, float]:
    """Wall-clock start and end of `steps` env steps (set-up excluded)."""
    env = RoboFollowEnv(episode=episode)
    env.reset()
    actions = _actions(steps)
    began = time.time()
    for action in actions:
        env.step(action)
    ended = time.time()
    env.close()
    return began, ended


def env_rate(episode: Episode, steps: int) -> float:
    began, ended = env_loop(episode, steps)
    return steps / (ended - began)


def bare_rate(episode: Episode, steps: int) -> float:
    """The same physics and frames with nothing of RoboFollow in the loop."""
    sim = Simulation(release.benchmark().spec.scenes[episode.scene], episode.layout)
    sim.reset(episode.seed)
    model, data = sim.model, sim.data
    renderer = mujoco.Renderer(model, 240, 320)
    ctrl = []
    for action in _actions(steps):  # each action's actuator targets, as the env sets them
        sim.apply(action)
        ctrl.append(data.ctrl.copy())
    began = time.perf_counter()
    for c in ctrl:
        data.ctrl[:] = c
        mujoco.mj_step(model, data, nstep=SUBSTEPS)
        for camera in CAMERA_NAMES:
            renderer.update_scene(data, camera)
            renderer.render()
    elapsed = time.perf_counter() - began
    renderer.close()
    return steps / elapsed


def _env_loop_job(args) -> tuple[float, float]:
    return env_loop(*args)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=positive, default=5)
    parser.add_argument("--steps", type=positive, default=150)
    parser.add_argument("--scene", default="scene4")
    parser.add_argument("--layout", default="scene4_1")
    args = parser.parse_args()
    try:
        scene_layout(release.benchmark(), args.scene, args.layout)
        episode = _episode_of(args.scene, args.layout)
    except RoboFollowError as error:
        parser.error(str(error))
    raw = [raw_physics(args.scene, args.layout, 20000) for _ in range(args.runs)]
    envs, bares, ratios = [], [], []
    for _ in range(args.runs):
        e, b = env_rate(episode, args.steps), bare_rate(episode, args.steps)
        envs.append(e)
        bares.append(b)
        ratios.append(b / e)  # time per step, env over bare
    pair = []
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        for _ in range(args.runs):
            spans = pool.map(_env_loop_job, [(episode, args.steps)] * 2)
            # both processes' steps over the wall time from the first start to the last end
            pair.append(2 * args.steps / (max(e for _, e in spans) - min(b for b, _ in spans)))
    print(f"scene {args.scene}/{args.layout}, {args.runs} runs (medians), "
          f"{SUBSTEPS} physics steps per control step, 3 cameras at 320x240")
    print(f"raw physics:                 {statistics.median(raw):10,.0f} steps/s")
    print(f"env, 1 process:              {statistics.median(envs):10.1f} control steps/s "
          "(target >= 50)")
    print(f"env, 2 processes together:   {statistics.median(pair):10.1f} control steps/s")
    print(f"bare MuJoCo, same work:      {statistics.median(bares):10.1f} control steps/s")
    print(f"env cost / bare cost:        {statistics.median(ratios):10.3f} (target <= 1.15)")


if __name__ == "__main__":
    main()
