"""The policy interface of the evaluation harness.

A policy is any object with

    uses: frozenset[str]          # which observation parts it reads (see OBSERVATION_PARTS)
    reset() -> None               # a new episode begins
    act(observation) -> [T, 14]   # the next chunk of absolute joint targets

The observation is a dict: "state" (float32 [14]), "instruction" (str), "step" (int, control
steps executed so far), and, only when the policy uses them, "images" ({cam_high,
cam_left_wrist, cam_right_wrist}: (H, W, 3) uint8) and "privileged" (a Privileged view of the
simulation, for the reference policies). Rendering only what a policy uses keeps image-free
policies fast.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from robofollow.compiler.behaviour import Behaviour
from robofollow.compiler.spec import Scene
from robofollow.compiler.world import World
from robofollow.errors import RoboFollowError
from robofollow.sim import robot
from robofollow.sim.simulation import Simulation

OBSERVATION_PARTS = frozenset({"state", "instruction", "images", "privileged"})
ACTION_WIDTH = len(robot.JOINT_NAMES)


@runtime_checkable
class Policy(Protocol):
    uses: frozenset[str]

    def reset(self) -> None: ...

    def act(self, observation: dict) -> np.ndarray: ...


@dataclass(frozen=True)
class Privileged:
    """What only a reference policy may see: the simulation at the episode start."""
    sim: Simulation
    world: World  # the settled start, measured
    scene: Scene
    training: dict[str, Behaviour]  # the scene's training behaviours by label
    seed: int  # the episode's seed, for policies that draw at random


class PolicyConnectionError(RoboFollowError):
    """A policy server could not be reached or did not answer, after the retries."""


class BadActionError(RoboFollowError):
    """A policy returned something that is not a chunk of finite joint targets."""


def validate_actions(actions) -> tuple[np.ndarray, np.ndarray]:
    """The chunk as float64 [T, 14] targets clipped to the joint limits, with which actions
    had a target past a limit (learned policies overshoot limits their demonstrations touch);
    BadActionError says what is wrong with a chunk that is not [T, 14] finite numbers."""
    try:
        chunk = np.asarray(actions, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise BadActionError(f"actions are not numbers: {error}") from None
    if chunk.ndim == 1 and chunk.shape == (ACTION_WIDTH,):
        chunk = chunk[None]
    if chunk.ndim != 2 or chunk.shape[1] != ACTION_WIDTH or len(chunk) == 0:
        raise BadActionError(f"actions must be [T, {ACTION_WIDTH}] with T >= 1, got shape "
                             f"{list(chunk.shape)}")
    if not np.all(np.isfinite(chunk)):
        row, column = np.argwhere(~np.isfinite(chunk))[0]
        raise BadActionError(f"action {row} has a non-finite value at "
                             f"{robot.JOINT_NAMES[column]}")
    return robot.clip_to_limits(chunk)
