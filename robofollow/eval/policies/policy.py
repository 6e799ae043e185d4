"""The policy interface of the evaluation harness.

A policy is any object with

    uses: frozenset[str]          # which observation parts it reads (see OBSERVATION_PARTS)
    reset() -> None               # a new episode begins
    act(observation) -> [T, 14]   # the next chunk of absolute joint targets

The observation is a dict: "state" (float32 [14]), "instruction" (str), "step" (int, control
steps executed so far; a served policy sees it only when its client sends it), and, only when
the policy uses them, "images" ({cam_high, cam_left_wrist, cam_right_wrist}: (H, W, 3) uint8),
"objects" (float32 [MAX_OBJECTS, len(FIELDS)]: every body's kind, size, colour, position and
yaw, as a perfect perception module would report them, in an order that carries no identity;
sim/objects.py) and "privileged" (a Privileged view of the simulation, for the reference
policies). Rendering only what a policy uses keeps image-free policies fast.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.compiler.scene.spec import Scene
from robofollow.compiler.scene.world import World
from robofollow.errors import RoboFollowError
from robofollow.eval.protocols.wire import server_text
from robofollow.sim import robot
from robofollow.sim.simulation import Simulation

OBSERVATION_PARTS = frozenset({"state", "instruction", "images", "objects", "privileged"})
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


def privileged_message(privileged: Privileged) -> dict:
    """The start a served reference policy rebuilds: {scene, layout, seed}."""
    return {"scene": privileged.scene.id, "layout": privileged.sim.layout,
            "seed": privileged.seed}


class PolicyConnectionError(RoboFollowError):
    """A policy server could not be reached or did not answer, after the retries."""


class PolicyServerError(RoboFollowError):
    """A policy server answered with an error, or with what its protocol does not allow
    (malformed metadata, bytes that are not a message, a message over the size limit)."""


class PrivilegedRefusedError(PolicyServerError):
    """A policy server asked for privileged observations that the user did not allow."""


class BadActionError(RoboFollowError):
    """A policy returned something that is not a chunk of finite joint targets."""


def declared_uses(metadata, default: frozenset, server: str,
                  allow_privileged: bool) -> frozenset:
    """The observation parts a RoboFollow server declares in its metadata
    ({"robofollow": {"uses": [part, ...]}}), or `default` for a server that declares none.
    A server may ask for "privileged" (each episode's scene, layout and seed) only where the
    user allowed it (`robofollow eval --allow-privileged`)."""
    if not isinstance(metadata, dict) or "robofollow" not in metadata:
        return default
    own = metadata["robofollow"]
    uses = own.get("uses") if isinstance(own, dict) else None
    if not isinstance(uses, list | tuple) or not all(isinstance(p, str) for p in uses):
        raise PolicyServerError(
            f"the policy server at {server} sent malformed metadata: 'robofollow' must be a "
            f"map whose 'uses' lists observation parts, got {server_text(repr(own))}")
    unknown = sorted(set(uses) - OBSERVATION_PARTS)
    if unknown:
        raise PolicyServerError(
            f"the policy server at {server} declares unknown observation parts "
            f"{server_text(', '.join(unknown))} (known: {', '.join(sorted(OBSERVATION_PARTS))})")
    if "privileged" in uses and not allow_privileged:
        raise PrivilegedRefusedError(
            f"the policy server at {server} asks for privileged observations (each episode's "
            "scene, layout and seed, from which it can rebuild the simulation's ground truth); "
            "they are sent only with `robofollow eval --allow-privileged` (the policy "
            "URL's ?privileged=1), which the run records")
    return frozenset(uses)


def validate_actions(actions) -> tuple[np.ndarray, np.ndarray]:
    """The chunk as float64 [T, 14] targets clipped to the joint limits, with which actions
    had a target past a limit (learned policies overshoot limits their demonstrations touch);
    BadActionError says what is wrong with a chunk that is not [T, 14] finite real numbers
    (strings, booleans, complex numbers and objects are refused, never converted)."""
    try:
        chunk = np.asarray(actions)
    except (TypeError, ValueError) as error:  # e.g. ragged nested lists
        raise BadActionError(f"actions are not numbers: {server_text(error)}") from None
    if chunk.dtype.kind not in "fiu":
        kind = {"b": "booleans", "c": "complex numbers", "U": "strings", "S": "bytes",
                "O": "objects"}.get(chunk.dtype.kind, f"dtype {chunk.dtype}")
        raise BadActionError(f"actions are not numbers: got {kind} (expected real joint "
                             "targets)")
    chunk = chunk.astype(np.float64)
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
