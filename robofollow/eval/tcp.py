"""Policies behind upstream RoboFollow's TCP protocol (`tcp://host:port`).

Each message is a 4-byte big-endian length and that many bytes of UTF-8 JSON. A request is
{"cmd": "reset" | "set_instruction" | "predict", "obs": ...} (the instruction string for
set_instruction); a reply is {"res": value} or {"error": ..., "traceback": ...}. numpy arrays
travel as {"__numpy_array__": true, "data": base64 bytes, "dtype", "shape"}. A predict
observation is {"observation": {"head_camera": {"rgb"}, "left_camera": {"rgb"},
"right_camera": {"rgb"}} (uint8 H x W x 3), "joint_action": {"vector"} (14), "instruction"};
its reply is the [T, 14] absolute joint targets.
"""

from __future__ import annotations

import base64
import json
import socket
import struct

import numpy as np

from robofollow.errors import RoboFollowError
from robofollow.eval.policy import PolicyConnectionError

MAX_MESSAGE = 128 * 2 ** 20  # bytes
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
    uses = frozenset({"state", "instruction", "images"})

    def __init__(self, host: str, port: int, timeout: float = 60.0, retries: int = 3):
        self.address, self.timeout, self.retries = (host, port), timeout, retries
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
        self._call("reset")
        self.instruction = None

    def act(self, observation: dict) -> np.ndarray:
        if observation["instruction"] != self.instruction:
            self._call("set_instruction", observation["instruction"])
            self.instruction = observation["instruction"]
        obs = {"observation": {CAMERAS[name]: {"rgb": image}
                               for name, image in observation["images"].items()},
               "joint_action": {"vector": np.asarray(observation["state"], dtype=np.float64)},
               "instruction": observation["instruction"]}
        return np.asarray(self._call("predict", obs))

    def close(self) -> None:
        if self.connection is not None:
            self.connection.close()
            self.connection = None
