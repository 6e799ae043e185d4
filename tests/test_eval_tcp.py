"""Upstream RoboFollow's TCP protocol: a minimal server written here from the protocol
description (length-prefixed JSON, base64 numpy arrays, reset / set_instruction / predict)."""

from __future__ import annotations

import base64
import json
import re
import socket
import struct
import threading

import numpy as np
import pytest

from robofollow.eval.policies.loading import PolicyLoadError, load_policy
from robofollow.eval.policies.policy import PolicyConnectionError
from robofollow.eval.policies.reference import ExpertPolicy
from robofollow.eval.policies.tcp_client import TcpPolicy
from robofollow.eval.running.episode import run_episode
from robofollow.eval.serving.tcp_server import TcpPolicyServer
from robofollow.sim import robot
from tests.sim_helpers import benchmark, episode, serve_process

EPISODE = "scene2/L0/pickup_left_cube#r1"


def _read(connection) -> dict | None:
    header = connection.recv(4, socket.MSG_WAITALL)
    if len(header) < 4:
        return None
    (size,) = struct.unpack(">I", header)
    return json.loads(connection.recv(size, socket.MSG_WAITALL))


def _write(connection, message) -> None:
    payload = json.dumps(message).encode()
    connection.sendall(struct.pack(">I", len(payload)) + payload)


def _array(data: np.ndarray) -> dict:
    return {"__numpy_array__": True, "data": base64.b64encode(data.tobytes()).decode(),
            "dtype": data.dtype.str, "shape": list(data.shape)}


def _unarray(value: dict) -> np.ndarray:
    return np.frombuffer(base64.b64decode(value["data"]), value["dtype"]).reshape(
        value["shape"])


class _Server:
    """Holds the observed state for 5 steps; `fail_predict` answers predict with an error;
    `drop_first_reset` closes the connection on the first reset."""

    def __init__(self, fail_predict=False, drop_first_reset=False):
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.port = self.listener.getsockname()[1]
        self.log: list = []
        self.fail_predict, self.drop_first_reset = fail_predict, drop_first_reset
        threading.Thread(target=self.run, daemon=True).start()

    def run(self):
        while True:
            try:
                connection, _ = self.listener.accept()
            except OSError:
                return
            with connection:
                while (request := _read(connection)) is not None:
                    self.log.append(request)
                    if request["cmd"] == "reset" and self.drop_first_reset:
                        self.drop_first_reset = False
                        break
                    if request["cmd"] == "predict":
                        if self.fail_predict:
                            _write(connection, {"error": "CUDA out of memory",
                                                "traceback": "..."})
                            continue
                        state = _unarray(request["obs"]["joint_action"]["vector"])
                        _write(connection, {"res": _array(np.repeat(state[None], 5, axis=0))})
                    else:
                        _write(connection, {"res": None})

    def close(self):
        self.listener.close()


@pytest.mark.slow
def test_an_upstream_style_server_is_driven_through_an_episode(stage):
    server = _Server()
    try:
        policy = load_policy(f"tcp://127.0.0.1:{server.port}")
        run = run_episode(benchmark(), stage, episode(EPISODE), policy, budget=20)
        policy.close()
    finally:
        server.close()
    assert run.error is None and (run.steps, run.queries) == (20, 4)
    commands = [r["cmd"] for r in server.log]
    assert commands == ["reset", "set_instruction"] + ["predict"] * 4
    assert server.log[1]["obs"] == episode(EPISODE).instruction
    obs = server.log[2]["obs"]
    assert set(obs["observation"]) == {"head_camera", "left_camera", "right_camera"}
    rgb = _unarray(obs["observation"]["head_camera"]["rgb"])
    assert rgb.shape == (240, 320, 3) and rgb.dtype == np.uint8
    assert obs["instruction"] == episode(EPISODE).instruction


def test_a_server_error_is_reported_with_its_message():
    server = _Server(fail_predict=True)
    try:
        policy = TcpPolicy("127.0.0.1", server.port, timeout=5)
        policy.reset()
        with pytest.raises(Exception, match="failed on 'predict': CUDA out of memory"):
            policy.act({"state": robot.home_state(), "instruction": "x",
                        "images": {"cam_high": np.zeros((2, 2, 3), np.uint8)}})
    finally:
        server.close()


def test_reset_is_retried_after_a_lost_connection():
    server = _Server(drop_first_reset=True)
    try:
        policy = TcpPolicy("127.0.0.1", server.port, timeout=5, retries=2)
        policy.reset()
    finally:
        server.close()
    assert [r["cmd"] for r in server.log] == ["reset", "reset"]


def test_no_server_and_bad_addresses_are_clear_errors():
    with pytest.raises(PolicyConnectionError, match="did not answer 'reset' after 2 tries"):
        TcpPolicy("127.0.0.1", 9, timeout=1, retries=1).reset()
    for spec in ("tcp://localhost", "tcp://localhost:80?speed=2", "tcp://h:80?timeout=x"):
        with pytest.raises(PolicyLoadError, match=re.escape(spec)):
            load_policy(spec)
    policy = load_policy("tcp://localhost:80?timeout=2.5&retries=7")
    assert (policy.timeout, policy.retries) == (2.5, 7)


def _serve_tcp(policy_spec: str) -> tuple[TcpPolicyServer, int]:
    """`robofollow serve --protocol tcp`'s server for `policy_spec`, in a thread."""
    server = TcpPolicyServer(benchmark(), policy_spec)
    ready, holder = threading.Event(), {}

    def on_ready(listener):
        holder["port"] = listener.getsockname()[1]
        ready.set()

    threading.Thread(target=server.serve_forever, args=("127.0.0.1", 0, on_ready),
                     daemon=True).start()
    assert ready.wait(30)
    return server, holder["port"]


@pytest.mark.slow
def test_the_tcp_served_expert_scores_as_the_in_process_expert(stage):
    server, port = _serve_tcp("expert")
    policy = load_policy(f"tcp://127.0.0.1:{port}?privileged=1")
    for episode_id in (EPISODE, "scene4/L0/s41_seq_l_bowl_then_r_green_cylinder#r2"):
        record = episode(episode_id)
        local = run_episode(benchmark(), stage, record, ExpertPolicy())
        remote = run_episode(benchmark(), stage, record, policy)
        assert policy.uses == {"instruction", "privileged"}  # declared in reset's answer
        assert remote.error is None and remote.score == local.score
        np.testing.assert_array_equal(remote.trajectory.action, local.trajectory.action)
    policy.close()


def test_the_tcp_server_answers_bad_requests_with_an_error_and_keeps_serving():
    server, port = _serve_tcp("noop")
    with socket.create_connection(("127.0.0.1", port), timeout=10) as connection:
        _write(connection, {"cmd": "dance", "obs": None})
        reply = _read(connection)
        assert reply["error"] == ("RequestError: unknown command 'dance' (expected reset, "
                                  "set_instruction or predict)")
        assert "Traceback" not in reply["traceback"]  # the message only, never the traceback
        _write(connection, {"cmd": "reset", "obs": None})
        assert _read(connection)["res"]["robofollow"]["uses"] == []
        _write(connection, {"cmd": "predict", "obs": {
            "observation": {}, "instruction": "stay",
            "joint_action": {"vector": _array(robot.home_state())}}})
        actions = _unarray(_read(connection)["res"])
    np.testing.assert_allclose(actions, np.repeat(robot.home_state()[None], 50, axis=0),
                               rtol=0, atol=1e-6)


def test_robofollow_serve_speaks_tcp_when_asked():
    with serve_process("--protocol", "tcp", "--host", "127.0.0.1") as (process, port):
        assert "serving noop on tcp://127.0.0.1:" in process.stdout.readline()
        policy = TcpPolicy("127.0.0.1", port, timeout=10)
        policy.reset()
        assert policy.uses == frozenset()
        actions = policy.act({"state": robot.home_state(), "instruction": "stay"})
        policy.close()
    assert actions.shape == (50, 14)
