"""One evaluation episode, as upstream's protocol: reset the episode's layout with its seed,
then query the policy for action chunks and execute them (at most CHUNK actions of each)
until the fixed action budget is spent; nothing ends an episode early except a policy failure
(an exception, SystemExit included, a chunk that is not [T, 14] finite numbers or, with a time
limit, a call that runs past it), which is recorded; KeyboardInterrupt still stops the caller.
Targets past a joint limit are clipped to it and counted. The recording is scored by the
oracle."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from robofollow.benchmark.episode import Benchmark, Episode
from robofollow.eval.policies.policy import (
    BadActionError,
    Policy,
    Privileged,
    validate_actions,
)
from robofollow.eval.running.deadline import PolicyTimeout, check_deadline, deadline
from robofollow.oracle.results import EpisodeScore
from robofollow.sim import CHUNK, MAX_STEPS, robot
from robofollow.sim.objects import observe_objects
from robofollow.sim.rollout import Rollout
from robofollow.sim.stage import Stage
from robofollow.trajectory import Trajectory


@dataclass
class EpisodeRun:
    score: EpisodeScore
    trajectory: Trajectory
    steps: int  # control steps executed
    queries: int  # policy calls
    clipped: int  # executed actions with a target past a joint limit (clipped to it)
    error: str | None  # why the policy stopped early, if it did
    seconds: float
    uses: frozenset[str] = frozenset()  # the observation parts the policy read


def observation(uses: frozenset[str], stage: Stage, instruction: str, steps: int,
                privileged: Privileged | None) -> dict:
    """What a policy that reads `uses` sees now: only those parts are computed (images are
    rendered)."""
    sim = stage.sim
    obs = {"state": robot.observed_state(sim.state()), "instruction": instruction,
           "step": steps}
    if "images" in uses:
        obs["images"] = stage.cameras.images()
    if "objects" in uses:
        obs["objects"] = observe_objects(sim)
    if privileged is not None:
        obs["privileged"] = privileged
    return obs


def _failure(failure: BaseException) -> str:
    if isinstance(failure, BadActionError | PolicyTimeout):
        return str(failure)
    if not isinstance(failure, Exception) or not str(failure):  # SystemExit(0), GeneratorExit()
        return f"the policy raised {failure!r}"
    return f"the policy raised {type(failure).__name__}: {failure}"


class PolicyRollout(Rollout):
    """A policy's episode in progress: the policy's calls so far and the executed actions whose
    targets were past a joint limit; each chunk runs at most CHUNK actions."""

    def __init__(self, compiled: Benchmark, stage: Stage, episode: Episode, render: bool,
                 budget: int = MAX_STEPS, on_frame=None):
        super().__init__(compiled, stage, episode, render, budget, on_frame)
        self.queries = self.clipped = 0

    def execute_chunk(self, chunk: np.ndarray, past: np.ndarray) -> None:
        """Run at most CHUNK actions of a validated chunk (`validate_actions`), within the
        budget."""
        executed = self.execute(chunk[:CHUNK])
        self.clipped += int(past[:executed].sum())

    def result(self, error: str | None, began: float, uses: frozenset[str]) -> EpisodeRun:
        """The recording scored by the oracle; `began`: perf_counter at the episode's start;
        `uses`: what the policy read."""
        score, trajectory = self.finish()
        return EpisodeRun(score, trajectory, self.steps, self.queries, self.clipped, error,
                          time.perf_counter() - began, uses)


def run_episode(compiled: Benchmark, stage: Stage, episode: Episode, policy: Policy | None,
                instruction: str | None = None, budget: int = MAX_STEPS,
                on_frame=None, timeout: float | None = None,
                failed: str | None = None) -> EpisodeRun:
    """Evaluate `policy` on a compiled episode. `instruction` replaces the episode's (the
    empty and shuffled controls); `on_frame(stage)` is called after every recorded frame;
    `timeout` limits each reset() and act() call to that many seconds. `failed`: the policy
    failed elsewhere (e.g. its process died) for this reason; the episode is scored as it
    stands at its start, without calling the policy (which may be None)."""
    check_deadline(timeout)  # (a misuse, not the policy's failure)
    began = time.perf_counter()
    error = failed
    if error is None:
        try:  # first: a served policy may declare what it uses in its answer
            with deadline(timeout):
                policy.reset()
        except KeyboardInterrupt:
            raise
        except BaseException as failure:  # noqa: B036 (e.g. its server is gone, SystemExit)
            error = f"reset: {_failure(failure)}"  # the episode is scored as it stands
    uses = policy.uses if policy is not None else frozenset()
    rollout = PolicyRollout(compiled, stage, episode, "images" in uses or on_frame is not None,
                      budget, on_frame)
    privileged = (Privileged(rollout.sim, rollout.world, rollout.scene,
                             compiled.candidates(rollout.scene.id), episode.seed)
                  if "privileged" in uses else None)
    text = episode.instruction if instruction is None else instruction
    while error is None and not rollout.done:
        rollout.queries += 1
        seen = observation(uses, stage, text, rollout.steps, privileged)
        try:
            with deadline(timeout):
                answer = policy.act(seen)
            chunk, past = validate_actions(answer)
        except KeyboardInterrupt:
            raise
        except BaseException as failure:  # noqa: B036 (a policy bug or exit ends its episode,
            error = f"step {rollout.steps}: {_failure(failure)}"  # not the evaluation)
            break
        rollout.execute_chunk(chunk, past)
    return rollout.result(error, began, uses)
