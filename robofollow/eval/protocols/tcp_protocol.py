"""Upstream RoboFollow's TCP protocol (`tcp://host:port`), as both ends speak it.

Each message is a 4-byte big-endian length and that many bytes of UTF-8 JSON. A request is
{"cmd": "reset" | "set_instruction" | "predict", "obs": ...} (the instruction string for
set_instruction); a reply is {"res": value} or {"error": ..., "traceback": ...}. numpy arrays
travel as {"__numpy_array__": true, "data": base64 bytes, "dtype", "shape"}. A predict
observation is {"observation": {"head_camera": {"rgb"}, "left_camera": {"rgb"},
"right_camera": {"rgb"}} (uint8 H x W x 3), "joint_action": {"vector"} (14), "instruction"};
its reply is the [T, 14] absolute joint targets. A message over the receiving end's limit
(`robofollow.eval.protocols.limits.MAX_MESSAGE_BYTES` unless configured) is refused unread.

Extensions only between RoboFollow ends: the server answers reset with {"robofollow":
{version, uses, observation}} (upstream servers answer None), and then the client sends only
the parts the policy uses, "step" (control steps executed so far) in each predict observation,
"objects" (the objects observation, float32 [MAX_OBJECTS, fields]) for a policy that reads it,
and "privileged" = {scene, layout, seed} in a reference policy's predict observations where
the user allowed it (`robofollow eval --allow-privileged`). Any client may send "step"; a step
of 0 after others begins a new episode.
"""

from __future__ import annotations

import base64
import binascii
import json
import socket
import struct
import time

import numpy as np

from robofollow.eval.protocols.limits import MAX_MESSAGE_BYTES
from robofollow.eval.protocols.wire import (
    MessageTooBig,
    WireError,
    server_text,
    size_text,
    wire_array,
)

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
            try:
                data = base64.b64decode(value.get("data"), validate=True)
            except (TypeError, ValueError, binascii.Error):
                raise WireError("an array's data is not base64") from None
            return wire_array(data, value.get("dtype"), value.get("shape"))
        return {key: decode(item) for key, item in value.items()}
    if isinstance(value, list):
        return [decode(item) for item in value]
    return value


def send_message(connection: socket.socket, message) -> None:
    payload = json.dumps(encode(message)).encode("utf-8")
    connection.sendall(struct.pack(">I", len(payload)) + payload)


def _receive_exactly(connection: socket.socket, size: int, deadline: float | None) -> bytes:
    chunks, left = [], size
    while left:
        if deadline is not None:  # the whole message within the time-out, not each piece
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise TimeoutError("the rest of the message did not arrive in time")
            connection.settimeout(remaining)
        chunk = connection.recv(min(left, 2 ** 20))
        if not chunk:
            raise ConnectionError("the connection closed mid-message")
        chunks.append(chunk)
        left -= len(chunk)
    return b"".join(chunks)


def receive_message(connection: socket.socket, max_size: int = MAX_MESSAGE_BYTES):
    """The next message. MessageTooBig: its length is over `max_size` (nothing of it is read;
    the connection is then out of step and must be closed). WireError: not JSON of the
    protocol. A connection with a time-out must deliver a message's rest within it."""
    timeout = connection.gettimeout()
    header = _receive_exactly(connection, 4, None)
    (size,) = struct.unpack(">I", header)
    if size > max_size:
        raise MessageTooBig(f"a message of {size_text(size)} is over the limit of "
                            f"{size_text(max_size)} (its first bytes: {header!r})")
    try:
        payload = _receive_exactly(
            connection, size, None if timeout is None else time.monotonic() + timeout)
    finally:
        connection.settimeout(timeout)
    try:
        return decode(json.loads(payload.decode("utf-8")))
    except WireError:
        raise
    except (ValueError, RecursionError) as error:  # not UTF-8 / JSON, or nested too deep
        raise WireError(f"not JSON: {type(error).__name__}: {server_text(error)}") from None
