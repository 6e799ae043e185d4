"""The objects observation: what a perfect perception module reports, with no identity in it;
read by policies in process and over both server protocols, offered by the Gymnasium
environment, recorded in datasets, and marked in the runs whose policy reads it."""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest

from robofollow.eval.running.episode import observation
from robofollow.eval.running.runner import EvalOptions, evaluate
from robofollow.eval.serving.serving import observation_layout
from robofollow.eval.serving.tcp_server import TcpPolicyServer
from robofollow.eval.serving.websocket_server import PolicyServer
from robofollow.sim.objects import FIELDS, SHAPE, _rows, objects_over, observe_objects
from robofollow.sim.recorder import Recorder
from robofollow.sim.stage import Stage
from tests.server_helpers import served
from tests.sim_helpers import benchmark, cached_benchmark


class ObjectsReader:
    """A policy that reads the state and the objects observation, and holds still."""
    uses = frozenset({"state", "objects"})
    seen: list = []

    def reset(self):
        pass

    def act(self, observation):
        objects = observation["objects"]
        assert objects.dtype == np.float32 and objects.shape == SHAPE
        assert "images" not in observation
        ObjectsReader.seen.append(objects)
        return observation["state"][None]


def make_objects_reader():
    return ObjectsReader()


def _stage(scene: str, layout: str = "default", seed: int = 3) -> Stage:
    stage = Stage(64, 48)
    stage.simulation(benchmark().spec.scenes[scene], layout).reset(seed)
    return stage


def test_each_body_is_one_row_of_kind_size_colour_pose_in_position_order():
    stage = _stage("scene2")
    sim = stage.sim
    found = observe_objects(sim)
    assert found.dtype == np.float32 and found.shape == SHAPE
    present = found[:, FIELDS.index("present")] == 1
    assert present.sum() == len(sim.bodies) and not found[~present].any()
    rows = found[present]
    x, y = FIELDS.index("x"), FIELDS.index("y")
    assert np.all(np.diff(rows[:, x]) >= 0)  # sorted by position
    for body, position in zip(sim.bodies, sim.positions(), strict=True):
        spec = sim.scene.bodies[body]
        [row] = [r for r in rows if np.allclose(r[x:y + 2], position, atol=1e-6)]
        assert row[FIELDS.index(f"is_{spec.kind}")] == 1
        assert np.allclose(row[FIELDS.index("size_x"):FIELDS.index("size_z") + 1],
                           2 * np.array(spec.half_extents))
        assert np.allclose(row[FIELDS.index("red"):FIELDS.index("blue") + 1], spec.rgb)
        assert np.isclose(np.hypot(row[FIELDS.index("yaw_sin")], row[FIELDS.index("yaw_cos")]),
                          1.0, atol=1e-6)
    stage.close()


def test_the_observation_carries_no_identity():
    """Two identical-looking bodies swapped give the same observation; the task and the
    instruction are not in it."""
    stage = _stage("scene1")
    sim = stage.sim
    twins = [b for b in sim.movable if sim.scene.bodies[b].kind == "cube"
             and sim.scene.bodies[b].color == "yellow"][:2]
    assert len(twins) == 2
    mujoco.mj_forward(sim.model, sim.data)  # positions as the swapped ones will be computed
    before = observe_objects(sim)
    first, second = (sim.free_qpos[b] for b in twins)
    qpos = sim.data.qpos
    qpos[first:first + 7], qpos[second:second + 7] = (qpos[second:second + 7].copy(),
                                                      qpos[first:first + 7].copy())
    mujoco.mj_forward(sim.model, sim.data)
    assert not np.allclose(sim.positions(), sim.positions()[::-1])  # the bodies did move
    assert np.array_equal(observe_objects(sim), before)
    seen = [observation(frozenset({"objects"}), stage, text, 0, None)["objects"]
            for text in ("Use your left arm to pick up the block.", "", "Push the ball.")]
    assert all(np.array_equal(s, before) for s in seen)
    stage.close()


def test_the_row_order_is_a_function_of_the_values_alone():
    """Bodies listed in any order give the same rows, also where two share x and y (a cube in
    a bowl): ties are broken by the other columns, never by the body's place in the layout."""
    rng = np.random.default_rng(0)
    looks = rng.random((5, 12))
    positions = rng.random((5, 3))
    positions[3, :2] = positions[1, :2]  # body 3 sits on body 1
    positions[4, 0] = positions[2, 0] + 1e-13  # an x within float noise of another's
    quaternions = rng.standard_normal((5, 4))
    quaternions /= np.linalg.norm(quaternions, axis=1, keepdims=True)
    rows = _rows(looks, positions, quaternions)
    for _ in range(6):
        order = rng.permutation(5)
        assert np.array_equal(_rows(looks[order], positions[order], quaternions[order]), rows)
    x = FIELDS.index("x")
    assert np.all(np.diff(rows[:5, x]) >= 0)


def test_a_recording_gives_at_every_frame_what_a_policy_reads_there():
    """The dataset's environment_state (objects_over a recording) equals the live
    observation at every frame."""
    stage = _stage("scene4", "scene4_1")  # a cube in the bowl: rows tied in x and y
    sim = stage.sim
    recorder, live = Recorder(sim), []
    rng = np.random.default_rng(1)
    action = sim.state()
    for _ in range(40):
        recorder.frame(action)
        live.append(observe_objects(sim))
        action = action + rng.normal(0, 0.02, size=action.shape)
        sim.step(action)
    recorded = objects_over(recorder.trajectory(), sim.scene, sim.layout)
    assert np.array_equal(recorded, np.stack(live))
    stage.close()


def test_servers_declare_the_objects_observation_and_pass_it_to_their_policy(tmp_path):
    layout = observation_layout(frozenset({"state", "objects"}), channels_first=True)
    assert layout["objects"] == {"dtype": "float32", "shape": list(SHAPE),
                                 "fields": list(FIELDS)}
    spec = "tests.test_objects_observation:make_objects_reader"
    for kind, server in (("ws", PolicyServer(benchmark(), spec)),
                         ("tcp", TcpPolicyServer(benchmark(), spec))):
        ObjectsReader.seen.clear()
        with served(server) as port:
            options = EvalOptions(f"{kind}://127.0.0.1:{port}", ("scene2",), ("L0",), 1,
                                  "normal", "none", benchmark().spec.digest,
                                  ("scene2/L0/pickup_left_cube",))
            result = evaluate(cached_benchmark(), tmp_path / kind, options, progress=False)
        assert result["observed"] == ["objects", "state"]  # as the server declares
        assert ObjectsReader.seen and all(s.shape == SHAPE for s in ObjectsReader.seen)


def test_a_run_whose_policy_reads_objects_says_perception_was_removed(tmp_path):
    options = EvalOptions("tests.test_objects_observation:make_objects_reader", ("scene3",),
                          ("L1",), 1, "normal", "none", benchmark().spec.digest, (), 1)
    result = evaluate(cached_benchmark(), tmp_path / "run", options, progress=False)
    assert result["observed"] == ["objects", "state"]
    from robofollow.eval.reports.report import write_report
    from robofollow.eval.reports.tables import table_text

    assert "Perception removed" in write_report(tmp_path / "run")[1].read_text()
    assert "\nObjects   perception removed: the policy read the objects" in table_text(result)
    both = dict(result, observed=["images", "objects", "state"])
    assert "ground truth added: the policy read the objects observation (ground truth) beside " \
        "camera images" in " ".join(table_text(both).split())
    assert "Objects" not in table_text(dict(result, observed=["images", "state"]))
    record = json.loads((tmp_path / "run" / "episodes.jsonl").read_text().splitlines()[0])
    assert record["observed"] == ["objects", "state"]


@pytest.mark.parametrize("objects", [False, True])
def test_the_gymnasium_environment_offers_the_objects_observation(objects):
    from robofollow.sim.env import RoboFollowEnv

    env = RoboFollowEnv("scene2/L0/pickup_left_cube#r1", width=64, height=48, objects=objects)
    obs, _ = env.reset()
    assert ("objects" in obs) == objects == ("objects" in env.observation_space.spaces)
    if objects:
        assert env.observation_space["objects"].contains(obs["objects"])
        obs, *_ = env.step(env.action_space.sample() * 0 + obs["state"])
        assert obs["objects"].shape == SHAPE
    env.close()
