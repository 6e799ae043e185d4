"""The Gymnasium environment."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from robofollow.benchmark.rounds import UnknownEpisodeError
from robofollow.compiler.planning.plans import plan
from robofollow.oracle.score import score
from robofollow.sim import robot
from robofollow.sim.env import RoboFollowEnv
from robofollow.sim.expert import Expert
from tests.sim_helpers import benchmark


@pytest.fixture(scope="module")
def env():
    environment = RoboFollowEnv(specs=None)
    yield environment
    environment.close()


def test_check_env_passes(env):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # advice about normalised action spaces
        check_env(env, skip_render_check=False)


def test_spaces(env):
    assert env.action_space.shape == (14,)
    np.testing.assert_allclose(env.action_space.low[[6, 13]], 0)
    np.testing.assert_allclose(env.action_space.high[[6, 13]], 1)
    np.testing.assert_allclose(env.action_space.low[:6], robot.JOINT_LOW, rtol=1e-6)
    images = env.observation_space["images"]
    assert set(images.keys()) == {"cam_high", "cam_left_wrist", "cam_right_wrist"}
    assert images["cam_high"].shape == (240, 320, 3)


def test_same_seed_same_state_and_images(env):
    first, info = env.reset(seed=123, options={"episode": "scene4/L0/s41_l_pick_blue_sphere#r2"})
    second, _ = env.reset(seed=123, options={"episode": "scene4/L0/s41_l_pick_blue_sphere#r2"})
    assert info["seed"] == 123 and info["layout"] == "scene4_1"
    assert np.array_equal(first["state"], second["state"])
    for name in first["images"]:
        assert np.array_equal(first["images"][name], second["images"][name])
    assert np.array_equal(env.sim.positions(), env.sim.positions())
    other, _ = env.reset(seed=124, options={"episode": "scene4/L0/s41_l_pick_blue_sphere#r2"})
    assert not np.array_equal(first["images"]["cam_high"], other["images"]["cam_high"])


def test_the_episode_sets_instruction_and_seed(env):
    obs, info = env.reset(options={"episode": "scene2/L0/pickup_left_cube#r3"})
    assert obs["instruction"] == "Use your left arm to pick up the leftmost cube."
    assert info["seed"] == next(e for e in _episodes() if e.id == info["episode"]).seed


def _episodes():
    from robofollow.benchmark.rounds import all_episodes

    return all_episodes(benchmark())


def test_expert_actions_through_the_env_achieve_the_behaviour(env):
    obs, info = env.reset(options={"episode": "scene2/L0/stack_left_cube_on_blue_cylinder#r1"})
    behaviour = env.episode.behaviour
    actions = Expert(env.sim).actions(plan(behaviour, env.sim.start_world))
    for action in actions:
        obs, reward, terminated, truncated, info = env.step(action.astype(np.float32))
        assert reward == 0.0 and not terminated
    assert info["step"] == len(actions)
    result = score(behaviour, env.trajectory(), env.sim.scene)
    assert result.complete and result.intent_score == result.execution_score == 1.0, \
        result.failures
    np.testing.assert_allclose(obs["state"][:6], actions[-1][:6], atol=0.03)


def test_truncation_and_bad_actions():
    env = RoboFollowEnv(max_steps=3, width=64, height=48)
    try:
        obs, _ = env.reset(seed=0)
        assert obs["images"]["cam_high"].shape == (48, 64, 3)
        flags = [env.step(robot.home_state())[3] for _ in range(3)]
        assert flags == [False, False, True]
        with pytest.raises(ValueError, match="14 finite joint targets"):
            env.step(np.zeros(13))
        with pytest.raises(ValueError, match="14 finite joint targets"):
            env.step(np.full(14, np.nan))
        with pytest.raises(UnknownEpisodeError, match="did you mean"):
            env.reset(options={"episode": "scene2/L0/pickup_left_cub#r1"})
    finally:
        env.close()
