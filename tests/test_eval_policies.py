"""The policy interface and the reference policies, one episode at a time."""

from __future__ import annotations

import signal
import time

import numpy as np
import pytest

from robofollow.compiler.scene import workspace
from robofollow.compiler.scene.world import World
from robofollow.errors import RoboFollowError
from robofollow.eval.policies.policy import BadActionError, validate_actions
from robofollow.eval.policies.reference import (
    REFERENCE_POLICIES,
    BlindPolicy,
    understood,
)
from robofollow.eval.running.chance import references
from robofollow.eval.running.episode import run_episode
from robofollow.oracle.chance import available_behaviours
from robofollow.sim import CHUNK, MAX_STEPS, robot
from tests.sim_helpers import benchmark, episode


def test_valid_chunks_pass_and_a_single_action_is_a_chunk_of_one():
    home = robot.home_state()
    chunk, past = validate_actions(home)
    assert chunk.shape == (1, 14) and past.tolist() == [False]
    nudged = home.copy()
    nudged[6] = 1.02  # a learned policy's "open", past the limit: clipped, not an error
    chunk, past = validate_actions([home, nudged])
    assert chunk[1, 6] == 1.0 and past.tolist() == [False, True]


@pytest.mark.parametrize("actions, message", [
    (np.zeros((3, 7)), r"\[T, 14\] with T >= 1, got shape \[3, 7\]"),
    (np.zeros((0, 14)), r"got shape \[0, 14\]"),
    ([[np.nan] * 14], "action 0 has a non-finite value at left_joint_0"),
    ([[np.inf] * 14], "action 0 has a non-finite value at left_joint_0"),
    ("go", "actions are not numbers"),
])
def test_invalid_chunks_say_what_is_wrong(actions, message):
    with pytest.raises(BadActionError, match=message):
        validate_actions(actions)


def test_a_joint_far_past_its_limit_is_clipped_to_it():
    action = robot.home_state()
    action[8] = 2.5  # right_joint_1, limit 1.2566
    chunk, past = validate_actions(action)
    assert chunk[0, 8] == robot.ACTION_HIGH[8] and past.tolist() == [True]


@pytest.mark.slow
@pytest.mark.parametrize("episode_id", [
    "scene1/L0/pickup_yellow_block_2#r1",
    "scene2/L0/pickup_left_cube#r1",
    "scene3/L0/r_pick2_via4_to6_long_front#r1",
])
def test_the_expert_policy_reads_the_instruction_and_scores_in_full(stage, episode_id):
    run = run_episode(benchmark(), stage, episode(episode_id), REFERENCE_POLICIES["expert"]())
    assert run.error is None and run.steps == MAX_STEPS
    assert run.score.complete and run.score.intent_score == run.score.execution_score == 1.0


@pytest.mark.slow
def test_given_another_tasks_instruction_the_expert_performs_that_task(stage):
    record = episode("scene2/L0/pickup_left_cube#r1")
    other = episode("scene2/L0/pickup_right_cube#r1")
    run = run_episode(benchmark(), stage, record, REFERENCE_POLICIES["expert"](),
                      instruction=other.instruction)
    assert run.score.intent_score == 0.0 and not run.score.complete
    assert run.score.executed_behaviour.match == "pickup_right_cube"


@pytest.mark.parametrize("scene, instruction, arm", [
    ("scene3", "Move the blue slab while avoiding passing over the red slab, then place it on "
               "the green square label with the long side facing right.", "left"),  # training
    ("scene2", "Put the red cube in the green bowl.", "right"),  # training places it right
    ("scene1", "Pick up the red cylinder.", "right"),  # never picked in training: nearer arm
    ("scene1", "Pick up the red ball.", "left"),
    ("scene1", "Pick up the block to the right of the red ball.", "left"),  # both in training
])
def test_an_arm_the_instruction_does_not_name_is_chosen_as_training_does_else_the_nearer(
        scene, instruction, arm):
    compiled = benchmark()
    world = World(compiled.spec.scenes[scene], "default")
    behaviour = understood(instruction, world, compiled.spec.scenes[scene],
                           compiled.candidates(scene))
    assert [step.arm for step in behaviour.steps] == [arm]


def test_every_paraphrase_a_shuffled_episode_can_give_is_understood_with_every_arm_set():
    compiled = benchmark()
    understood_count = 0
    for scene in compiled.spec.scenes.values():
        for layout in scene.layouts:
            world = World(scene, layout)
            for text in sorted({p for task in scene.tasks for p in task.paraphrases}):
                try:
                    behaviour = understood(text, world, scene, compiled.candidates(scene.id))
                except RoboFollowError:  # names an object this layout lacks: the expert holds
                    continue
                understood_count += 1
                assert all(step.arm in workspace.ARMS for step in behaviour.steps), (layout, text)
    assert understood_count > 1000


@pytest.mark.slow
def test_the_expert_follows_an_instruction_that_names_no_arm(stage):
    record = episode("scene3/L0/l_pick5_around2_to1_long_right#r1")
    armless = ("Move the blue slab while avoiding passing over the red slab, then place it on "
               "the green square label with the long side facing right.")
    run = run_episode(benchmark(), stage, record, REFERENCE_POLICIES["expert"](),
                      instruction=armless)
    assert run.error is None and run.score.complete and run.score.intent_score == 1.0
    assert references(benchmark(), record, armless)["followed_intent"] == 1.0


@pytest.mark.slow
def test_noop_spends_the_budget_in_chunks_and_scores_nothing(stage):
    run = run_episode(benchmark(), stage, episode("scene1/L0/pickup_yellow_block_2#r1"),
                      REFERENCE_POLICIES["noop"]())
    assert (run.steps, run.queries) == (MAX_STEPS, MAX_STEPS // CHUNK)
    assert run.score.intent_score == run.score.execution_score == 0.0


@pytest.mark.slow
def test_blind_performs_one_available_training_behaviour_chosen_by_the_seed(stage):
    record = episode("scene2/L0/pickup_left_cube#r1")
    first = run_episode(benchmark(), stage, record, BlindPolicy())
    again = run_episode(benchmark(), stage, record, BlindPolicy())
    np.testing.assert_array_equal(first.trajectory.action, again.trajectory.action)
    match = first.score.executed_behaviour.match
    labels = available_behaviours(stage.sim.start_world, benchmark().candidates("scene2"))
    assert match in labels and first.score.executed_behaviour.intent_score == 1.0


class _Raises:
    uses = frozenset({"state"})

    def reset(self):
        self.calls = 0

    def act(self, observation):
        self.calls += 1
        if self.calls == 3:
            raise RuntimeError("model crashed")
        return np.repeat(observation["state"][None], 50, axis=0)


class _Returns:
    uses = frozenset({"state"})

    def __init__(self, value):
        self.value = value

    def reset(self):
        pass

    def act(self, observation):
        return self.value


@pytest.mark.slow
@pytest.mark.parametrize("policy, steps, message", [
    (_Raises(), 100, "step 100: the policy raised RuntimeError: model crashed"),
    (_Returns(np.full((5, 14), np.nan)), 0, "step 0: action 0 has a non-finite value"),
    (_Returns(np.zeros((5, 12))), 0, "step 0: actions must be [T, 14]"),
])
def test_a_failing_policy_ends_its_episode_with_the_reason_and_is_scored(stage, policy,
                                                                         steps, message):
    run = run_episode(benchmark(), stage, episode("scene1/L0/pickup_yellow_block_2#r1"),
                      policy)
    assert run.steps == steps and run.error.startswith(message)
    assert run.score.intent_score == 0.0


class _Hangs:
    """Answers until its call `hang_at` (0: reset), which sleeps far past any time limit."""
    uses = frozenset({"state"})

    def __init__(self, hang_at):
        self.hang_at = hang_at

    def reset(self):
        self.calls = 0
        if self.hang_at == 0:
            time.sleep(600)

    def act(self, observation):
        self.calls += 1
        if self.calls == self.hang_at:
            time.sleep(600)
        return np.repeat(observation["state"][None], 50, axis=0)


@pytest.mark.parametrize("hang_at, steps, message", [
    (2, 50, "step 50: the policy did not answer within 0.5 s"),
    (0, 0, "reset: the policy did not answer within 0.5 s"),
])
def test_a_policy_that_hangs_past_its_time_limit_ends_its_episode(stage, hang_at, steps,
                                                                  message):
    run = run_episode(benchmark(), stage, episode("scene1/L0/pickup_yellow_block_2#r1"),
                      _Hangs(hang_at), timeout=0.5)
    assert (run.steps, run.error) == (steps, message)
    assert run.score.intent_score == 0.0
    assert signal.getitimer(signal.ITIMER_REAL) == (0.0, 0.0)  # the timer is cleared
    assert signal.getsignal(signal.SIGALRM) is signal.SIG_DFL  # and the handler restored


def test_a_time_limit_leaves_a_policy_within_it_alone(stage):
    run = run_episode(benchmark(), stage, episode("scene1/L0/pickup_yellow_block_2#r1"),
                      _Hangs(hang_at=-1), timeout=30)
    assert (run.steps, run.error) == (MAX_STEPS, None)


@pytest.mark.slow
def test_the_expert_holds_in_full_chunks_once_its_plan_is_done(stage):
    run = run_episode(benchmark(), stage, episode("scene2/L0/pickup_left_cube#r1"),
                      REFERENCE_POLICIES["expert"]())
    # full chunks, and one short chunk where the plan ends (not one query per held step)
    assert run.queries <= MAX_STEPS // CHUNK + 1
