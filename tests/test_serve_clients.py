"""`robofollow serve` facing clients that are not RoboFollow's: a policy is reset for each
connection and when a client's step starts again at 0, the step reaches the policy through both
protocols, observations are checked against the declared layout (with an error reply saying
what was expected), `/healthz` answers 200 on both ports, and a reference policy tells a client
that cannot send privileged observations why it cannot drive it."""

from __future__ import annotations

import base64
import socket
import time
import urllib.error
import urllib.request

import numpy as np
import pytest
from websockets.sync.client import connect

from robofollow.eval.policies.tcp_client import TcpPolicy
from robofollow.eval.policies.websocket_client import WebsocketPolicy
from robofollow.eval.protocols.wire import packb, unpackb
from robofollow.eval.serving.serving import ServerLimits
from robofollow.eval.serving.tcp_server import TcpPolicyServer
from robofollow.eval.serving.websocket_server import PolicyServer
from robofollow.sim import robot
from robofollow.sim.cameras import CAMERA_NAMES, IMAGE_HEIGHT, IMAGE_WIDTH
from tests.server_helpers import WAIT, _array, _client, _frame, _read, served
from tests.sim_helpers import benchmark

HOME = robot.home_state().astype(np.float32)
UPSTREAM_CAMERAS = ("head_camera", "left_camera", "right_camera")


class Counting:
    """Answers [[acts since reset, step or -1, 1 if it saw images]]: its state shows."""

    def __init__(self, uses):
        self.uses, self.count = frozenset(uses), 0

    def reset(self) -> None:
        self.count = 0

    def act(self, observation: dict) -> np.ndarray:
        self.count += 1
        row = np.zeros((1, 14))
        row[0, :3] = self.count, observation.get("step", -1), "images" in observation
        return row


def counting():
    return Counting({"state", "instruction"})


def seeing():
    return Counting({"state", "instruction", "images"})


def _released(server) -> None:
    """Wait until the last connection's policy instance is back in the pool (the next
    connection then takes the same instance)."""
    deadline = time.monotonic() + WAIT
    while not server.pool.idle:
        assert time.monotonic() < deadline, "the policy instance was not released"
        time.sleep(0.01)


def _images(shape=(3, IMAGE_HEIGHT, IMAGE_WIDTH), dtype=np.uint8) -> dict:
    return {camera: np.zeros(shape, dtype) for camera in CAMERA_NAMES}


def _ws_infer(connection, observation: dict):
    connection.send(packb(observation))
    reply = connection.recv(timeout=WAIT)
    return reply if isinstance(reply, str) else unpackb(reply)["actions"][0]


def _openpi_observation(**parts) -> dict:
    return {"state": HOME, "prompt": "pick up the cube", "images": _images(), **parts}


def _tcp_predict(connection, state=HOME, images=None, step=None) -> dict:
    obs = {"observation": {name: {"rgb": _array(image)} for name, image in (images or {}).items()},
           "joint_action": {"vector": _array(np.asarray(state, np.float64))},
           "instruction": "pick up the cube"}
    if step is not None:
        obs["step"] = step
    connection.sendall(_frame({"cmd": "predict", "obs": obs}))
    return _read(connection)


def _counts(res) -> tuple:
    """(acts since reset, step, saw images) from a Counting policy's reply."""
    row = np.frombuffer(base64.b64decode(res["data"]), res["dtype"]).reshape(res["shape"])[0]
    return tuple(int(v) for v in row[:3])


# -- episode boundaries ------------------------------------------------------------------------

def test_an_openpi_client_gets_a_fresh_policy_on_each_connection():
    server = PolicyServer(benchmark(), "tests.test_serve_clients:counting")
    with served(server) as port:
        for _ in range(2):  # the same instance both times (one client at a time)
            _released(server)
            with connect(f"ws://127.0.0.1:{port}", compression=None, open_timeout=WAIT) as ws:
                unpackb(ws.recv(timeout=WAIT))
                counts = [int(_ws_infer(ws, _openpi_observation())[0]) for _ in range(3)]
            assert counts == [1, 2, 3]


def test_a_step_of_zero_begins_a_new_episode_on_the_same_connection():
    server = PolicyServer(benchmark(), "tests.test_serve_clients:counting")
    with served(server) as port:
        with connect(f"ws://127.0.0.1:{port}", compression=None, open_timeout=WAIT) as ws:
            unpackb(ws.recv(timeout=WAIT))
            seen = [tuple(_ws_infer(ws, _openpi_observation(step=step))[:2].astype(int))
                    for step in (0, 50, 100, 0, 50)]
            plain = _ws_infer(ws, _openpi_observation())  # a client that sends no step
    assert seen == [(1, 0), (2, 50), (3, 100), (1, 0), (2, 50)]
    assert tuple(plain[:2].astype(int)) == (3, -1)  # no step: the policy sees none


def test_a_tcp_client_gets_a_fresh_policy_on_each_connection_and_steps_reach_it():
    server = TcpPolicyServer(benchmark(), "tests.test_serve_clients:counting")
    with served(server) as port:
        for _ in range(2):
            with _client(port) as connection:  # upstream's client: no reset, no step
                counts = [_counts(_tcp_predict(connection)["res"])[:2] for _ in range(2)]
            assert counts == [(1, -1), (2, -1)]
        _released(server)
        with _client(port) as connection:
            steps = [_counts(_tcp_predict(connection, step=step)["res"])[:2]
                     for step in (0, 50, 0)]
        assert steps == [(1, 0), (2, 50), (1, 0)]


@pytest.mark.parametrize("protocol", ["ws", "tcp"])
def test_robofollow_clients_pass_the_episode_step_to_a_served_policy(protocol):
    server_class = PolicyServer if protocol == "ws" else TcpPolicyServer
    server = server_class(benchmark(), "tests.test_serve_clients:counting")
    with served(server) as port:
        policy = (WebsocketPolicy(f"ws://127.0.0.1:{port}", timeout=WAIT) if protocol == "ws"
                  else TcpPolicy("127.0.0.1", port, timeout=WAIT))
        seen = []
        for _ in range(2):  # two episodes
            policy.reset()
            seen += [tuple(np.asarray(policy.act(
                {"state": HOME, "instruction": "x", "step": step}))[0, :2].astype(int))
                for step in (0, 50)]
        policy.close()
    assert seen == [(1, 0), (2, 50), (1, 0), (2, 50)]


# -- observations checked against the declared layout ------------------------------------------

def test_the_metadata_declares_the_observation_layout():
    server = PolicyServer(benchmark(), "tests.test_serve_clients:seeing")
    with served(server) as port:
        policy = WebsocketPolicy(f"ws://127.0.0.1:{port}", timeout=WAIT)
        layout = policy.metadata["robofollow"]["observation"]
        policy.close()
    assert layout["state"] == {"dtype": "float32", "shape": [14]}
    assert layout["images"]["cam_high"] == {"dtype": "uint8",
                                            "shape": [3, IMAGE_HEIGHT, IMAGE_WIDTH]}


@pytest.mark.parametrize("parts, message", [
    ({"images": _images((IMAGE_HEIGHT, IMAGE_WIDTH, 3))},
     "image 'cam_high' must be uint8 [3, 240, 320] (channels first, openpi's convention); got "
     "uint8 [240, 320, 3]"),
    ({"images": _images(dtype=np.float32)}, "image 'cam_high' must be uint8 [3, 240, 320]"),
    ({"images": _images((1, 3, IMAGE_HEIGHT, IMAGE_WIDTH))}, "got uint8 [1, 3, 240, 320]"),
    ({"images": {"cam_high": np.zeros((3, IMAGE_HEIGHT, IMAGE_WIDTH), np.uint8)}},
     "'images' has no 'cam_left_wrist'"),
    ({"images": None}, "reads the camera images and the observation has none"),
    ({"state": HOME[None]}, "'state' must be 14 numbers (shape [14], no batch axis), got shape "
                            "[1, 14]"),
    ({"prompt": 3}, "the instruction ('prompt') must be a string"),
    ({"step": -2}, "'step' must be a whole number"),
], ids=["hwc", "float", "batched", "camera", "none", "state-batch", "prompt", "step"])
def test_a_malformed_observation_gets_an_error_reply_saying_what_was_expected(parts, message):
    server = PolicyServer(benchmark(), "tests.test_serve_clients:seeing")
    observation = {key: value for key, value in _openpi_observation(**parts).items()
                   if value is not None}
    with served(server) as port:
        with connect(f"ws://127.0.0.1:{port}", compression=None, open_timeout=WAIT) as ws:
            unpackb(ws.recv(timeout=WAIT))
            reply = _ws_infer(ws, observation)
        _released(server)
        with connect(f"ws://127.0.0.1:{port}", compression=None, open_timeout=WAIT) as ws:
            unpackb(ws.recv(timeout=WAIT))
            good = _ws_infer(ws, _openpi_observation())  # still serving, images seen
    assert isinstance(reply, str) and reply.startswith("RequestError: ") and message in reply
    assert tuple(good[[0, 2]].astype(int)) == (1, 1)


def test_the_tcp_server_checks_images_in_upstreams_layout():
    server = TcpPolicyServer(benchmark(), "tests.test_serve_clients:seeing")
    upstream = dict(zip(UPSTREAM_CAMERAS, _images((IMAGE_HEIGHT, IMAGE_WIDTH, 3)).values(),
                        strict=True))
    transposed = dict(zip(UPSTREAM_CAMERAS, _images().values(), strict=True))
    with served(server) as port, _client(port) as connection:
        good = _tcp_predict(connection, images=upstream)
        bad = _tcp_predict(connection, images=transposed)
        missing = _tcp_predict(connection, images={"head_camera": upstream["head_camera"]})
    assert _counts(good["res"])[2] == 1
    assert ("image 'head_camera' must be uint8 [240, 320, 3] (height, width, channels: "
            "upstream's convention); got uint8 [3, 240, 320]") in bad["error"]
    assert "predict's 'observation' has no 'left_camera'" in missing["error"]


def test_images_a_policy_does_not_read_are_not_checked():
    server = PolicyServer(benchmark(), "tests.test_serve_clients:counting")
    with served(server) as port:
        with connect(f"ws://127.0.0.1:{port}", compression=None, open_timeout=WAIT) as ws:
            unpackb(ws.recv(timeout=WAIT))
            reply = _ws_infer(ws, _openpi_observation(images=_images((224, 224, 3))))
    assert tuple(reply[[0, 2]].astype(int)) == (1, 0)


# -- health checks and reference policies ------------------------------------------------------

def _http_status(port: int, path: str) -> tuple[int, str]:
    try:
        with urllib.request.urlopen(f"http://127.0.0.1:{port}{path}", timeout=WAIT) as reply:
            return reply.status, reply.read().decode()
    except urllib.error.HTTPError as error:
        return error.code, ""


@pytest.mark.parametrize("server_class", [PolicyServer, TcpPolicyServer], ids=["ws", "tcp"])
def test_healthz_answers_200_on_both_protocols_and_the_server_goes_on(server_class):
    server = server_class(benchmark(), "noop")
    with served(server) as port:
        assert _http_status(port, "/healthz") == (200, "OK\n")
        other = _http_status(port, "/")[0]
        policy = (WebsocketPolicy(f"ws://127.0.0.1:{port}", timeout=WAIT)
                  if server_class is PolicyServer else TcpPolicy("127.0.0.1", port, timeout=WAIT))
        policy.reset()
        assert np.asarray(policy.act({"state": HOME, "instruction": "x"})).shape == (50, 14)
        policy.close()
    assert other == (426 if server_class is PolicyServer else 404)


def test_a_served_reference_policy_tells_an_openpi_client_why_it_cannot_drive_it():
    server = PolicyServer(benchmark(), "expert")
    with served(server) as port:
        with connect(f"ws://127.0.0.1:{port}", compression=None, open_timeout=WAIT) as ws:
            metadata = unpackb(ws.recv(timeout=WAIT))
            reply = _ws_infer(ws, _openpi_observation())
    assert "privileged" in metadata["robofollow"]["uses"]
    assert isinstance(reply, str) and "KeyError" not in reply
    assert "reference policy that reads privileged observations" in reply
    assert "--allow-privileged" in reply and "Other clients (openpi's) cannot drive it" in reply


def test_a_client_that_sends_nothing_is_not_taken_for_a_health_check():
    server = TcpPolicyServer(benchmark(), "noop", ServerLimits(idle_timeout=0.5))
    with served(server) as port, _client(port) as connection:
        connection.sendall(b"GE")  # not a whole request: the idle time-out closes it
        with pytest.raises((ConnectionError, socket.timeout)):
            if connection.recv(1) == b"":
                raise ConnectionError("closed")
