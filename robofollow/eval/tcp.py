"""Policies behind upstream RoboFollow's TCP protocol (`tcp://host:port`).

Each message is a 4-byte big-endian length and that many bytes of UTF-8 JSON. A request is
{"cmd": "reset" | "set_instruction" | "predict", "obs": ...} (the instruction string for
set_instruction); a reply is {"res": value} or {"error": ..., "traceback": ...}. numpy arrays
travel as {"__numpy_array__": true, "data": base64 bytes, "dtype", "shape"}. A predict
observation is {"observation": {"head_camera": {"rgb"}, "left_camera": {"rgb"},
"right_camera": {"rgb"}} (uint8 H x W x 3), "joint_action": {"vector"} (14), "instruction"};
its reply is the [T, 14] absolute joint targets.

`robofollow serve --protocol tcp` puts a Python policy behind this protocol, each connection
in its own thread with its own policy instance. Its error replies carry the error's message;
"traceback" says only that the traceback is in the server's log. A message over the receiving
end's limit (`robofollow.eval.limits.MAX_MESSAGE_BYTES` unless configured) is refused unread: the
server answers with an error and closes the connection, the client fails the call.

The server also answers an HTTP `GET /healthz` on its port with 200, checks each predict
observation against the layout it declares on reset ("robofollow": {"observation": ...}), and
resets its policy for each connection.

Extensions only between RoboFollow ends: the server answers reset with {"robofollow":
{version, uses, observation}} (upstream servers answer None), and then the client sends only
the parts the policy uses, "step" (control steps executed so far) in each predict observation,
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
import threading
import time

import numpy as np

from robofollow.build import Compiled
from robofollow.eval.limits import CALL_TIMEOUT_S, DEFAULT_HOST, MAX_MESSAGE_BYTES
from robofollow.eval.policy import (
    PolicyConnectionError,
    PolicyServerError,
    declared_uses,
    server_text,
)
from robofollow.eval.serving import (
    PolicyPool,
    RequestError,
    ServerBusyError,
    ServerLimits,
    checked_images,
    error_reply,
    log,
    privileged_message,
)
from robofollow.eval.wire import (
    MessageTooBig,
    WireError,
    size_text,
    wire_array,
)

UPSTREAM_USES = frozenset({"state", "instruction", "images"})
CAMERAS = {"cam_high": "head_camera", "cam_left_wrist": "left_camera",
           "cam_right_wrist": "right_camera"}
TRACEBACK_NOTE = "not sent; see the server's log"


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


class TcpPolicy:
    """A policy served by upstream's TCP protocol. `reset` is retried after a lost
    connection (as upstream's client does); a lost `predict` is retried once the connection
    is back, up to `retries` times. Replies over `max_message` bytes or not of the protocol
    fail the call at once. `privileged`: whether a server may ask for privileged
    observations."""

    def __init__(self, host: str, port: int, timeout: float = CALL_TIMEOUT_S, retries: int = 3,
                 max_message: int = MAX_MESSAGE_BYTES, privileged: bool = False):
        self.address, self.timeout, self.retries = (host, port), timeout, retries
        self.max_message, self.allow_privileged = max_message, privileged
        self.uses = UPSTREAM_USES
        self.robofollow = False  # whether the server is RoboFollow's (said on reset)
        self.connection: socket.socket | None = None
        self.instruction: str | None = None

    @property
    def uri(self) -> str:
        return f"tcp://{self.address[0]}:{self.address[1]}"

    def _call(self, cmd: str, obs=None):
        for attempt in range(self.retries + 1):
            try:
                if self.connection is None:
                    self.connection = socket.create_connection(self.address, self.timeout)
                    self.connection.settimeout(self.timeout)
                send_message(self.connection, {"cmd": cmd, "obs": obs})
                reply = receive_message(self.connection, self.max_message)
                break
            except MessageTooBig as error:  # retrying would bring the same reply
                self.close()
                raise PolicyServerError(f"the policy server at {self.uri} answered {cmd!r} "
                                        f"with {error} (raise it with "
                                        "?max_message=BYTES)") from None
            except WireError as error:
                self.close()
                raise PolicyServerError(f"the policy server at {self.uri} answered {cmd!r} "
                                        "with a message that is not upstream's protocol: "
                                        f"{error}") from None
            except OSError as error:  # (ConnectionError and time-outs included)
                self.close()
                if attempt == self.retries:
                    raise PolicyConnectionError(
                        f"the policy server at {self.uri} did not answer {cmd!r} after "
                        f"{self.retries + 1} tries: {error}") from None
        if not isinstance(reply, dict) or not ({"res", "error"} & set(reply)):
            self.close()
            raise PolicyServerError(f"the policy server at {self.uri} answered {cmd!r} with "
                                    f"{server_text(repr(reply))}, not {{'res': ...}} or "
                                    "{'error': ...}")
        if "error" in reply:
            raise PolicyServerError(f"the policy server failed on {cmd!r}: "
                                    f"{server_text(reply['error'])}")
        return reply["res"]

    def reset(self) -> None:
        reply = self._call("reset")
        self.robofollow = isinstance(reply, dict) and "robofollow" in reply
        try:
            self.uses = declared_uses(reply, UPSTREAM_USES, self.uri, self.allow_privileged)
        except PolicyServerError:
            self.close()
            raise
        self.instruction = None

    def act(self, observation: dict) -> np.ndarray:
        if observation["instruction"] != self.instruction:
            self._call("set_instruction", observation["instruction"])
            self.instruction = observation["instruction"]
        obs = {"observation": {CAMERAS[name]: {"rgb": image}
                               for name, image in observation.get("images", {}).items()},
               "joint_action": {"vector": np.asarray(observation["state"], dtype=np.float64)},
               "instruction": observation["instruction"]}
        if self.robofollow and "step" in observation:
            obs["step"] = int(observation["step"])
        if "privileged" in observation and self.allow_privileged:
            obs["privileged"] = privileged_message(observation["privileged"])
        return self._call("predict", obs)  # checked by the episode (validate_actions)

    def close(self) -> None:
        if self.connection is not None:
            self.connection.close()
            self.connection = None


def _drain(connection: socket.socket, limit: int = 2 ** 20, seconds: float = 1.0) -> None:
    """Close our side, then read (and drop) what the client still sends for a moment, so
    that the reply just sent is not lost to a reset of a connection with unread data."""
    try:
        connection.shutdown(socket.SHUT_WR)
        connection.settimeout(seconds)
        deadline, read = time.monotonic() + seconds, 0
        while read < limit and time.monotonic() < deadline:
            chunk = connection.recv(65536)
            if not chunk:
                return
            read += len(chunk)
    except OSError:
        pass


HTTP_REQUEST_LIMIT = 8192  # bytes of an HTTP request's head read for a health check


def _answer_http(connection: socket.socket) -> None:
    """A health check on the server's port: `GET /healthz` is 200, any other path 404."""
    head = b""
    while b"\r\n\r\n" not in head and len(head) < HTTP_REQUEST_LIMIT:
        chunk = connection.recv(HTTP_REQUEST_LIMIT - len(head))
        if not chunk:
            break
        head += chunk
    path = head.split(b"\r\n", 1)[0].split(b" ")[1:2]
    status, body = ("200 OK", b"OK\n") if path == [b"/healthz"] else \
        ("404 Not Found", b"this port speaks RoboFollow's TCP protocol; GET /healthz checks it\n")
    connection.sendall(f"HTTP/1.1 {status}\r\nContent-Type: text/plain\r\nContent-Length: "
                       f"{len(body)}\r\nConnection: close\r\n\r\n".encode() + body)


class _Session:
    """One connection's state: its policy instance and the instruction last set."""

    def __init__(self, pool: PolicyPool):
        self.pool, self.served, self.instruction = pool, None, ""

    def answer(self, request):
        if not isinstance(request, dict):
            raise RequestError("a request must be {'cmd': ..., 'obs': ...}")
        command, obs = request.get("cmd"), request.get("obs")
        if command not in ("reset", "set_instruction", "predict"):
            raise RequestError(f"unknown command {server_text(repr(command))} (expected reset, "
                               "set_instruction or predict)")
        if self.served is None:
            self.served = self.pool.acquire()
        if command == "reset":
            self.served.reset()
            self.instruction = ""
            return self.served.metadata(channels_first=False)
        if command == "set_instruction":
            if not isinstance(obs, str):
                raise RequestError("set_instruction's obs must be the instruction string")
            self.instruction = obs
            return None
        if not isinstance(obs, dict) or not isinstance(obs.get("joint_action"), dict):
            raise RequestError("predict's obs must be {'observation', 'joint_action': "
                               "{'vector'}, 'instruction'}")
        cameras = obs.get("observation") or {}
        if not isinstance(cameras, dict) or not all(
                isinstance(cameras[key], dict) for key in CAMERAS.values() if key in cameras):
            raise RequestError("predict's 'observation' must map head_camera, left_camera and "
                               "right_camera to {'rgb': array}")
        images = {name: cameras[key].get("rgb") for name, key in CAMERAS.items()
                  if key in cameras} or None
        if images is not None and "images" in self.pool.uses:
            images = checked_images(images, channels_first=False, names=CAMERAS,
                                    where="predict's 'observation'")
        return self.served.act(obs["joint_action"].get("vector"),
                               obs.get("instruction", self.instruction), images,
                               obs.get("privileged"), obs.get("step"))

    def close(self) -> None:
        if self.served is not None:
            self.pool.release(self.served)
            self.served = None


class TcpPolicyServer:
    """Serves one Python policy over upstream's TCP protocol, each connection in a thread."""

    def __init__(self, compiled: Compiled, policy_spec: str,
                 limits: ServerLimits | None = None):
        self.limits = limits or ServerLimits()
        self.pool = PolicyPool(compiled, policy_spec, self.limits.max_clients)
        self.stopped = threading.Event()
        self.slots = threading.BoundedSemaphore(self.limits.max_clients)

    def handle(self, connection: socket.socket, peer="client") -> None:
        """Answer one connection's requests until it closes, idles past the time-out, sends
        a message over the limit or bytes that are not the protocol; or, for an HTTP
        request, its health check."""
        session = _Session(self.pool)
        with connection:
            connection.settimeout(self.limits.idle_timeout)
            try:
                if connection.recv(4, socket.MSG_PEEK | socket.MSG_WAITALL) == b"GET ":
                    _answer_http(connection)
                    return
                while not self.stopped.is_set():
                    try:
                        request = receive_message(connection, self.limits.max_message)
                    except (MessageTooBig, WireError) as error:  # refused, then closed
                        log.warning("%s: %s", peer, error)
                        send_message(connection, {"error": f"{type(error).__name__}: {error}",
                                                  "traceback": TRACEBACK_NOTE})
                        _drain(connection)
                        return
                    try:
                        reply = {"res": session.answer(request)}
                    except Exception as error:  # the message only; the traceback is logged
                        reply = {"error": error_reply(error, str(peer)),
                                 "traceback": TRACEBACK_NOTE}
                    try:
                        send_message(connection, reply)
                    except (TypeError, ValueError) as error:  # a reply JSON cannot carry
                        send_message(connection, {"error": error_reply(error, str(peer)),
                                                  "traceback": TRACEBACK_NOTE})
            except OSError:  # closed, reset, or idle past the time-out
                return
            except Exception:  # never the server: only this connection ends
                log.exception("%s: connection failed", peer)
            finally:
                session.close()

    def serve_forever(self, host: str = DEFAULT_HOST, port: int = 0, ready=None) -> None:
        with socket.create_server((host, port)) as listener:
            listener.settimeout(0.5)  # to notice shutdown()
            if ready is not None:
                ready(listener)
            while not self.stopped.is_set():
                try:
                    connection, peer = listener.accept()
                except TimeoutError:
                    continue
                if not self.slots.acquire(blocking=False):  # refused, not queued
                    self._refuse(connection, peer)
                    continue
                threading.Thread(target=self._serve_one, args=(connection, peer), daemon=True,
                                 name=f"robofollow-tcp-{peer}").start()

    def _serve_one(self, connection: socket.socket, peer) -> None:
        try:
            self.handle(connection, peer)
        finally:
            self.slots.release()

    def _refuse(self, connection: socket.socket, peer) -> None:
        with connection:
            error = ServerBusyError(f"the server is serving its limit of "
                                    f"{self.limits.max_clients} clients; try again later")
            try:
                connection.settimeout(1.0)
                send_message(connection, {"error": error_reply(error, str(peer)),
                                          "traceback": TRACEBACK_NOTE})
            except OSError:
                pass

    def shutdown(self) -> None:
        """Stop accepting; open connections end at their next message."""
        self.stopped.set()
