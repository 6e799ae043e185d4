"""Policies behind upstream RoboFollow's TCP protocol (`tcp://host:port`).

Each message is a 4-byte big-endian length and that many bytes of UTF-8 JSON. A request is
{"cmd": "reset" | "set_instruction" | "predict", "obs": ...} (the instruction string for
set_instruction); a reply is {"res": value} or {"error": ..., "traceback": ...}. numpy arrays
travel as {"__numpy_array__": true, "data": base64 bytes, "dtype", "shape"}. A predict
observation is {"observation": {"head_camera": {"rgb"}, "left_camera": {"rgb"},
"right_camera": {"rgb"}} (uint8 H x W x 3), "joint_action": {"vector"} (14), "instruction"};
its reply is the [T, 14] absolute joint targets.

`robofollow serve --protocol tcp` puts a Python policy behind this protocol. Extensions only
between RoboFollow ends: the server answers reset with {"robofollow": {version, uses}} (upstream
servers answer None), and then the client sends only the parts the policy uses, with
"privileged" = {scene, layout, seed} in a reference policy's predict observations.
"""

from __future__ import annotations

import base64
import json
import socket
import struct
import traceback

import numpy as np

from robofollow.build import Compiled
from robofollow.errors import RoboFollowError
from robofollow.eval.policy import OBSERVATION_PARTS, PolicyConnectionError
from robofollow.eval.serving import ServedPolicy, privileged_message

MAX_MESSAGE = 128 * 2 ** 20  # bytes
UPSTREAM_USES = frozenset({"state", "instruction", "images"})
CAMERAS = {"cam_high": "head_camera", "cam_left_wrist": "left_camera",
           "cam_right_wrist": "right_camera"}


def encode(value):
    """JSON-ready value, arrays in upstream's tagged form."""
    if isinstance(value, np.ndarray):
        return {"__numpy_array__": True, "data": base64.b64encode(
            np.ascontiguousarray(value).tobytes()).decode("ascii"),
            "dtype": value.dtype.str, "shape": list(value.shape)}
    if isinstance(value, dict):
        return {key: encode(item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [encode(item) for item in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def decode(value):
    if isinstance(value, dict):
        if value.get("__numpy_array__"):
            data = base64.b64decode(value["data"])
            return np.frombuffer(data, dtype=np.dtype(value["dtype"])).reshape(value["shape"])
        return {key: decode(item) for key, item in value.items()}
    if isinstance(value, list):
        return [decode(item) for item in value]
    return value


def send_message(connection: socket.socket, message) -> None:
    payload = json.dumps(encode(message)).encode("utf-8")
    connection.sendall(struct.pack(">I", len(payload)) + payload)


def _receive_exactly(connection: socket.socket, size: int) -> bytes:
    chunks, left = [], size
    while left:
        chunk = connection.recv(min(left, 2 ** 20))
        if not chunk:
            raise ConnectionError("the connection closed mid-message")
        chunks.append(chunk)
        left -= len(chunk)
    return b"".join(chunks)


def receive_message(connection: socket.socket):
    (size,) = struct.unpack(">I", _receive_exactly(connection, 4))
    if size > MAX_MESSAGE:
        raise ConnectionError(f"a message of {size} bytes is over the {MAX_MESSAGE} limit")
    return decode(json.loads(_receive_exactly(connection, size).decode("utf-8")))


class TcpPolicy:
    """A policy served by upstream's TCP protocol. `reset` is retried after a lost
    connection (as upstream's client does); a lost `predict` is retried once the connection
    is back, up to `retries` times."""

    def __init__(self, host: str, port: int, timeout: float = 60.0, retries: int = 3):
        self.address, self.timeout, self.retries = (host, port), timeout, retries
        self.uses = UPSTREAM_USES
        self.connection: socket.socket | None = None
        self.instruction: str | None = None

    def _call(self, cmd: str, obs=None):
        for attempt in range(self.retries + 1):
            try:
                if self.connection is None:
                    self.connection = socket.create_connection(self.address, self.timeout)
                    self.connection.settimeout(self.timeout)
                send_message(self.connection, {"cmd": cmd, "obs": obs})
                reply = receive_message(self.connection)
                break
            except (OSError, ConnectionError) as error:
                self.close()
                if attempt == self.retries:
                    raise PolicyConnectionError(
                        f"the policy server at tcp://{self.address[0]}:{self.address[1]} did "
                        f"not answer {cmd!r} after {self.retries + 1} tries: {error}") from None
        if "error" in reply:
            raise RoboFollowError(f"the policy server failed on {cmd!r}: {reply['error']}")
        return reply.get("res")

    def reset(self) -> None:
        reply = self._call("reset")
        declared = reply.get("robofollow", {}).get("uses") if isinstance(reply, dict) else None
        self.uses = (frozenset(declared) & OBSERVATION_PARTS if declared is not None
                     else UPSTREAM_USES)
        self.instruction = None

    def act(self, observation: dict) -> np.ndarray:
        if observation["instruction"] != self.instruction:
            self._call("set_instruction", observation["instruction"])
            self.instruction = observation["instruction"]
        obs = {"observation": {CAMERAS[name]: {"rgb": image}
                               for name, image in observation.get("images", {}).items()},
               "joint_action": {"vector": np.asarray(observation["state"], dtype=np.float64)},
               "instruction": observation["instruction"]}
        if "privileged" in observation:
            obs["privileged"] = privileged_message(observation["privileged"])
        return np.asarray(self._call("predict", obs))

    def close(self) -> None:
        if self.connection is not None:
            self.connection.close()
            self.connection = None


class TcpPolicyServer:
    """Serves one Python policy over upstream's TCP protocol, one connection at a time."""

    def __init__(self, compiled: Compiled, policy_spec: str):
        self.served = ServedPolicy(compiled, policy_spec)
        self.instruction = ""

    def handle(self, connection: socket.socket) -> None:
        with connection:
            while True:
                try:
                    request = receive_message(connection)
                except (OSError, ConnectionError, ValueError):  # closed, or not this protocol
                    return
                try:
                    reply = {"res": self._answer(request)}
                except Exception as error:  # the client gets the message and the traceback
                    reply = {"error": f"{type(error).__name__}: {error}",
                             "traceback": traceback.format_exc()}
                send_message(connection, reply)

    def _answer(self, request: dict):
        command, obs = request.get("cmd"), request.get("obs")
        if command == "reset":
            self.served.reset()
            self.instruction = ""
            return self.served.metadata
        if command == "set_instruction":
            self.instruction = obs
            return None
        if command == "predict":
            cameras = obs.get("observation", {})
            images = {name: cameras[key]["rgb"] for name, key in CAMERAS.items()
                      if key in cameras} or None
            return self.served.act(obs["joint_action"]["vector"],
                                   obs.get("instruction", self.instruction), images,
                                   obs.get("privileged"))
        raise ValueError(f"unknown command {command!r} (expected reset, set_instruction or "
                         "predict)")

    def serve_forever(self, host: str, port: int, ready=None) -> None:
        with socket.create_server((host, port)) as listener:
            if ready is not None:
                ready(listener)
            while True:
                connection, _ = listener.accept()
                self.handle(connection)
