"""The openpi websocket path end to end: `robofollow serve`'s server with the expert behind it
gives the in-process scores; a minimal openpi-style server written here from the protocol
description; lost connections and time-outs."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest
from websockets.sync.server import serve

from robofollow.eval.policies.policy import PolicyConnectionError
from robofollow.eval.policies.reference import ExpertPolicy
from robofollow.eval.policies.websocket_client import WebsocketPolicy
from robofollow.eval.protocols.wire import packb, unpackb
from robofollow.eval.running.episode import run_episode
from robofollow.eval.serving.websocket_server import PolicyServer
from robofollow.sim import robot
from tests.sim_helpers import benchmark, cached_benchmark, episode

EPISODE = "scene2/L0/pickup_left_cube#r1"


def _start(handler) -> tuple[str, object]:
    """Serve `handler` on a free local port in a thread; returns the uri and the server."""
    holder = {}
    ready = threading.Event()

    def run():
        with serve(handler, "127.0.0.1", 0, compression=None, max_size=None) as server:
            holder["server"] = server
            ready.set()
            server.serve_forever()

    threading.Thread(target=run, daemon=True).start()
    assert ready.wait(10)
    server = holder["server"]
    return f"ws://127.0.0.1:{server.socket.getsockname()[1]}", server


@pytest.mark.slow
def test_the_served_expert_scores_as_the_in_process_expert(stage):
    record = episode(EPISODE)
    local = run_episode(benchmark(), stage, record, ExpertPolicy())
    uri, server = _start(PolicyServer(benchmark(), "expert").handle)
    try:
        remote_policy = WebsocketPolicy(uri, privileged=True)
        assert remote_policy.uses == {"instruction", "privileged"}
        remote = run_episode(benchmark(), stage, record, remote_policy)
        remote_policy.close()
    finally:
        server.shutdown()
    assert remote.error is None
    assert remote.score == local.score
    np.testing.assert_array_equal(remote.trajectory.action, local.trajectory.action)


@pytest.mark.slow
def test_a_served_baseline_checkpoint_acts_as_the_in_process_one(stage):
    from robofollow.eval.policies.loading import load_policy

    record = episode(EPISODE)
    local = run_episode(benchmark(), stage, record, load_policy("baseline:scene2-text"))
    uri, server = _start(PolicyServer(benchmark(), "baseline:scene2-text").handle)
    try:
        remote_policy = WebsocketPolicy(uri)
        remote = run_episode(benchmark(), stage, record, remote_policy)
        remote_policy.close()
    finally:
        server.shutdown()
    assert remote.error is None and local.error is None
    assert remote.score == local.score
    np.testing.assert_allclose(remote.trajectory.action, local.trajectory.action, atol=1e-6)


def _openpi_like(seen: list):
    """A server written from the protocol description only: metadata first, then one reply
    {"actions": [H, 14]} per observation; it holds the observed state for 10 steps."""
    def handler(connection):
        connection.send(packb({"action_horizon": 10}))
        for data in connection:
            obs = unpackb(data)
            seen.append(obs)
            connection.send(packb({"actions": np.repeat(obs["state"][None], 10, axis=0)}))
    return handler


@pytest.mark.slow
def test_an_openpi_style_server_gets_aloha_observations(stage):
    seen: list = []
    uri, server = _start(_openpi_like(seen))
    try:
        policy = WebsocketPolicy(uri)
        run = run_episode(benchmark(), stage, episode(EPISODE), policy, budget=30)
        policy.close()
    finally:
        server.shutdown()
    assert run.error is None and (run.steps, run.queries) == (30, 3)
    first = seen[0]
    assert set(first) == {"state", "images", "prompt"}
    assert first["prompt"] == episode(EPISODE).instruction
    assert first["state"].dtype == np.float32 and first["state"].shape == (14,)
    assert {k: v.shape for k, v in first["images"].items()} == {
        name: (3, 240, 320) for name in ("cam_high", "cam_left_wrist", "cam_right_wrist")}
    assert first["images"]["cam_high"].dtype == np.uint8


def test_a_server_that_stops_answering_is_retried_then_reported():
    calls = []

    def silent(connection):
        connection.send(packb({}))
        for _ in connection:
            calls.append(time.monotonic())  # never answers

    uri, server = _start(silent)
    try:
        policy = WebsocketPolicy(uri, timeout=0.3, retries=2)
        with pytest.raises(PolicyConnectionError, match="did not answer after 3 tries"):
            policy.act({"state": robot.home_state(), "instruction": "x"})
    finally:
        server.shutdown()
    assert len(calls) == 3


def test_a_lost_connection_is_reopened():
    served = []

    def flaky(connection):
        connection.send(packb({}))
        for data in connection:
            served.append(unpackb(data)["prompt"])
            if len(served) == 1:
                connection.close()  # drop the first request
                return
            connection.send(packb({"actions": np.zeros((2, 14), np.float32)}))

    uri, server = _start(flaky)
    try:
        policy = WebsocketPolicy(uri, timeout=5, retries=2)
        actions = policy.act({"state": robot.home_state(), "instruction": "again"})
    finally:
        server.shutdown()
    assert actions.shape == (2, 14) and served == ["again", "again"]


def test_no_server_is_a_clear_error():
    with pytest.raises(PolicyConnectionError, match="cannot reach the policy server"):
        WebsocketPolicy("ws://127.0.0.1:9", timeout=2)


def test_robofollow_serve_runs_a_policy_server(tmp_path):
    from tests.sim_helpers import serve_process

    with serve_process("--host", "127.0.0.1") as (process, port):
        assert "serving noop on ws://127.0.0.1:" in process.stdout.readline()
        policy = WebsocketPolicy(f"ws://127.0.0.1:{port}", timeout=10)
        assert policy.metadata["robofollow"]["uses"] == [] and policy.uses == frozenset()
        policy.reset()
        actions = policy.act({"state": robot.home_state(), "instruction": "stay"})
        policy.close()
    np.testing.assert_allclose(actions, np.repeat(robot.home_state()[None], 50, axis=0),
                               rtol=0, atol=1e-6)


@pytest.mark.slow
def test_a_server_killed_mid_run_costs_its_episodes_not_the_run(tmp_path):
    from robofollow.eval.running.runner import EvalOptions, evaluate, read_results

    holder = {}

    def dies_after_two_chunks(connection):
        connection.send(packb({}))
        for count, data in enumerate(connection, start=1):
            obs = unpackb(data)
            connection.send(packb({"actions": np.repeat(obs["state"][None], 50, axis=0)}))
            if count == 2:
                threading.Thread(target=holder["server"].shutdown).start()
                connection.close()
                return

    uri, holder["server"] = _start(dies_after_two_chunks)
    options = EvalOptions(uri + "?timeout=1&retries=1", ("scene2",), ("L0",), 1, "normal",
                          "none", benchmark().spec.digest,
                          ("scene2/L0/pickup_left_cube", "scene2/L0/pickup_right_cube"))
    summary = evaluate(cached_benchmark(), tmp_path / "run", options, progress=False)
    records = {r["task"]: r for r in read_results(tmp_path / "run" / "episodes.jsonl")}
    assert summary["episodes"] == 2
    first, second = (records[f"scene2/L0/{name}"] for name in ("pickup_left_cube",
                                                               "pickup_right_cube"))
    assert first["steps"] == 100 and "PolicyConnectionError" in first["error"]
    assert second["steps"] == 0 and "PolicyConnectionError" in second["error"]
