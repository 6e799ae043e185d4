"""IK, the scripted expert on every action kind, the recorded trajectory."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robofollow.sim import robot
from robofollow.sim.expert import Expert
from robofollow.sim.ik import ArmIK, top_down
from robofollow.sim.rollout import run_expert
from robofollow.sim.simulation import Simulation
from robofollow.trajectory import Trajectory
from tests.sim_helpers import benchmark, cached_benchmark, episode

# one episode per action kind and scene, across levels (layout changes and rewordings)
KINDS = [
    "scene1/L0/pickup_yellow_block_2#r1",
    "scene1/L0/place_yellow_block_1_behind_red_cylinder#r2",
    "scene1/L0/place_yellow_block_3_in_front_of_green_sphere#r3",
    "scene2/L0/pickup_blue_cylinder#r1",
    "scene2/L0/stack_left_cube_on_red_cylinder#r4",
    "scene2/L0/push_red_cylinder_to_left_cube#r2",
    "scene2/L0/place_blue_cylinder_in_yellow_bowl#r5",
    "scene3/L0/r_pick3_via5_to6_long_front#r1",
    "scene3/L0/l_pick4_around2_to1_short_right#r2",
    "scene4/L0/s41_l_pick_cube_in_bowl#r1",
    "scene4/L0/s41_r_unstack_green_cylinder_to_slot6#r3",
    "scene4/L0/s43_r_stack_blue_cube_on_right_cylinder#r1",
    "scene4/L0/s41_seq_r_green_cylinder_then_l_bowl#r2",
    "scene4/L0/s41_if_object_on_right_cube_then_r_stack_else_l_pick_blue#r1",
]


@pytest.mark.parametrize("episode_id", KINDS)
def test_the_expert_scores_in_full_on_every_kind_of_behaviour(episode_id):
    record = episode(episode_id)
    result = run_expert(benchmark(), record)
    assert result.achieved, result.score.failures
    assert result.score.intent_score == result.score.execution_score == 1.0
    trajectory = result.trajectory
    assert len(trajectory) == result.steps + 1
    actions = trajectory.action
    assert np.all(actions >= robot.ACTION_LOW) and np.all(actions <= robot.ACTION_HIGH)
    # smooth: no joint target jumps more than 0.25 rad between control steps
    assert np.max(np.abs(np.diff(actions[:, :6], axis=0))) < 0.25
    assert np.max(np.abs(np.diff(actions[:, 7:13], axis=0))) < 0.25


@pytest.mark.parametrize("episode_id", [e for e in KINDS if "L0" in e][:3] + [
    "scene2/L0/push_red_cylinder_to_left_cube#r2"])
def test_the_expert_is_deterministic(episode_id):
    record = episode(episode_id)
    a, b = run_expert(benchmark(), record).trajectory, run_expert(benchmark(), record).trajectory
    assert np.array_equal(a.positions, b.positions) and np.array_equal(a.action, b.action)


def test_other_levels_and_layouts():
    """The expert performs a generated task of each other level (the working compile's)."""
    compiled = benchmark()
    for level in ("L1", "L2", "L3"):
        task = next(t for t in compiled.splits.tasks if t.level == level and t.scene == "scene2")
        record = cached_benchmark().record(f"{task.id}#r1")
        result = run_expert(compiled, record)
        assert result.achieved, (task.id, result.score.failures)


def test_a_pick_is_held_and_recorded_as_grasped():
    record = episode("scene2/L0/pickup_left_cube#r1")
    trajectory = run_expert(benchmark(), record).trajectory
    cube = trajectory.index("large_blue_cube")
    assert trajectory.grasped[0, 0] == -1 and trajectory.grasped[-1, 0] == cube
    assert trajectory.grasped[-1, 1] == -1
    assert trajectory.gripper[0, 0] == pytest.approx(1.0, abs=0.02)
    assert trajectory.gripper[-1, 0] < 0.9  # closed on the cube
    left = trajectory.contact_names.index("left_gripper")
    assert trajectory.contacts[-1, cube, left] and trajectory.contacts[-1, left, cube]
    assert trajectory.contacts[0, cube, trajectory.contact_names.index("table")]


def test_trajectory_save_and_load(tmp_path):
    record = episode("scene3/L0/r_pick2_via4_to6_short_front#r1")
    trajectory = run_expert(benchmark(), record).trajectory
    trajectory.save(tmp_path / "t.npz")
    loaded = Trajectory.load(tmp_path / "t.npz")
    assert loaded.bodies == trajectory.bodies and loaded.meta == trajectory.meta
    for name in ("positions", "quaternions", "state", "action", "grasped", "contacts"):
        assert np.array_equal(getattr(loaded, name), getattr(trajectory, name))
    assert isinstance(loaded.positions, np.ndarray) and loaded.meta["seed"] == record.seed


@pytest.mark.parametrize("arm", [0, 1])
def test_ik_reaches_the_workspace_top_down(arm):
    sim = Simulation(benchmark().spec.scenes["scene1"], "default")
    ik = ArmIK(sim.model, sim.arm_qpos[arm], sim.arm_dof[arm], sim.tcp_sites[arm])
    rng = np.random.default_rng(arm)
    expert = Expert(sim)
    for _ in range(25):
        target = np.array([rng.uniform(-0.2, 0.2), rng.uniform(-0.25, 0.0), rng.uniform(0.75, 0.9)])
        yaw = rng.uniform(-math.pi / 2, math.pi / 2)
        q = expert.reach(arm, target, yaw)
        position, rotation = ik.forward(q)
        assert np.linalg.norm(position - target) < 1e-3
        assert abs(rotation[2, 0] + 1) < 1e-3  # the gripper points straight down
        closing = math.atan2(rotation[1, 1], rotation[0, 1])
        assert min(abs(closing - yaw) % math.pi, math.pi - abs(closing - yaw) % math.pi) < 0.01
        assert np.all(q >= robot.JOINT_LOW) and np.all(q <= robot.JOINT_HIGH)
    np.testing.assert_allclose(top_down(0.0)[:, 1], [1, 0, 0], atol=1e-12)
