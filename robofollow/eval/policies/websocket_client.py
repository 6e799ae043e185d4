"""The client of the openpi websocket protocol: a policy served at `ws://host:port`.

Protocol (openpi's): on connect the server sends its metadata (a msgpack map); then each
client message is an observation and each reply a map with "actions" ([H, 14]). Messages are
msgpack with numpy arrays (robofollow.eval.protocols.wire). Observations follow openpi's ALOHA
convention: "state" (float32 [14]), "images" {cam_high, cam_left_wrist, cam_right_wrist} as
uint8 [3, H, W], "prompt" (the instruction). A server that fails sends a text message and
closes. Either end closes the connection (code 1009) on a message over its size limit
(`protocols.limits.MAX_MESSAGE_BYTES` unless configured); the client then fails the call with
the reason, without retrying.

Extensions only between RoboFollow ends (an openpi server never sees them): a server whose
metadata carries "robofollow" accepts {"reset": true} at an episode start, receives "step"
(control steps executed so far) with each observation, declares the observation parts its
policy uses, receives "objects" (float32 [MAX_OBJECTS, fields]) for a policy that reads the
objects observation, and for a privileged (reference) policy receives "privileged" = {scene, layout,
seed}, from which it rebuilds the same start state itself, where the user allowed it
(`robofollow eval --allow-privileged`). Any client may send "step"; a step of 0 after others
begins a new episode.
"""

from __future__ import annotations

from contextlib import ExitStack

import numpy as np
from websockets.exceptions import ConnectionClosed, InvalidURI, WebSocketException
from websockets.frames import CloseCode
from websockets.sync.client import connect

from robofollow.eval.policies.policy import (
    PolicyConnectionError,
    PolicyServerError,
    declared_uses,
    privileged_message,
)
from robofollow.eval.protocols.limits import CALL_TIMEOUT_S, MAX_MESSAGE_BYTES
from robofollow.eval.protocols.wire import (
    WireError,
    packb,
    server_text,
    size_text,
    unpackb,
)

OPENPI_USES = frozenset({"state", "instruction", "images"})


def _too_big(error: ConnectionClosed) -> str | None:
    """Which end refused a message as too big, if that is why the connection closed: "rcvd"
    (the peer closed first, with 1009, and this end echoed it) or "sent" (this end did)."""
    too_big = CloseCode.MESSAGE_TOO_BIG
    if error.rcvd is not None and error.rcvd.code == too_big and (
            error.sent is None or error.rcvd_then_sent):
        return "rcvd"
    if error.sent is not None and error.sent.code == too_big:
        return "sent"
    return None


class WebsocketPolicy:
    """A policy served over the openpi websocket protocol (`ws://host:port`). Messages over
    `max_message` bytes are refused; `privileged`: whether the server may ask for privileged
    observations."""

    def __init__(self, uri: str, timeout: float = CALL_TIMEOUT_S, retries: int = 3,
                 max_message: int = MAX_MESSAGE_BYTES, privileged: bool = False):
        self.uri, self.timeout, self.retries = uri, timeout, retries
        self.max_message, self.allow_privileged = max_message, privileged
        self.connection = None
        self.metadata = self._connect()
        try:
            self.uses = declared_uses(self.metadata, OPENPI_USES, uri, privileged)
        except PolicyServerError:
            self.close()
            raise

    def _connect(self) -> dict:
        self.close()
        self.exits = ExitStack()
        try:
            self.connection = self.exits.enter_context(connect(
                self.uri, compression=None, max_size=self.max_message,
                open_timeout=self.timeout))
            data = self.connection.recv(timeout=self.timeout)
        except ConnectionClosed as error:
            self.close()
            if _too_big(error):
                raise PolicyServerError(self._too_big_text(error, "its metadata")) from None
            raise PolicyConnectionError(f"cannot reach the policy server at {self.uri}: "
                                        f"{error}") from None
        except (OSError, TimeoutError, InvalidURI, WebSocketException) as error:
            self.close()
            raise PolicyConnectionError(f"cannot reach the policy server at {self.uri}: "
                                        f"{type(error).__name__}: {error}") from None
        return self._message(data, "metadata")

    def _message(self, data: str | bytes, what: str) -> dict:
        """A message from the server as a map; its error text, or anything that is not a
        msgpack-numpy map, is a PolicyServerError (and the connection is closed)."""
        if isinstance(data, str):  # a text message: the server's error
            self.close()
            raise PolicyServerError(f"the policy server at {self.uri} failed: "
                                    f"{server_text(data)}")
        try:
            message = unpackb(data)
        except WireError as error:
            self.close()
            raise PolicyServerError(f"the policy server at {self.uri} sent {what} that is "
                                    f"not msgpack-numpy: {error}") from None
        if not isinstance(message, dict):
            self.close()
            raise PolicyServerError(f"the policy server at {self.uri} sent {what} that is "
                                    f"not a map: {server_text(repr(message))}")
        return message

    def _too_big_text(self, error: ConnectionClosed, what: str) -> str:
        if _too_big(error) == "sent":
            return (f"the policy server at {self.uri} sent {what} over this client's limit of "
                    f"{size_text(self.max_message)} (raise it with ?max_message=BYTES)")
        return (f"the policy server at {self.uri} refused a message as over its size limit "
                f"({server_text(error.rcvd.reason)}; `robofollow serve --max-message` raises "
                "it)")

    def _call(self, message: dict) -> dict:
        """Send one message and return the reply, reconnecting on a lost connection or a
        time-out (up to `retries` times); a message over either end's limit, or a reply
        that is not the protocol, fails at once."""
        for attempt in range(self.retries + 1):
            try:
                if self.connection is None:
                    self._connect()
                self.connection.send(packb(message))
                reply = self.connection.recv(timeout=self.timeout)
            except ConnectionClosed as error:
                self.close()
                if _too_big(error):
                    raise PolicyServerError(self._too_big_text(error, "a reply")) from None
                failure = error
            except (OSError, TimeoutError, PolicyConnectionError) as error:
                self.close()
                failure = error
            else:
                break
            if attempt == self.retries:
                raise PolicyConnectionError(
                    f"the policy server at {self.uri} did not answer after "
                    f"{self.retries + 1} tries: {type(failure).__name__}: {failure}") from None
        return self._message(reply, "a reply")

    def reset(self) -> None:
        if "robofollow" in self.metadata:
            self._call({"reset": True})

    def act(self, observation: dict) -> np.ndarray:
        message = {"state": np.asarray(observation["state"], dtype=np.float32),
                   "prompt": observation.get("instruction", "")}
        if "robofollow" in self.metadata and "step" in observation:
            message["step"] = int(observation["step"])
        if "images" in observation:
            message["images"] = {camera: np.ascontiguousarray(image.transpose(2, 0, 1))
                                 for camera, image in observation["images"].items()}
        if "objects" in observation:
            message["objects"] = np.asarray(observation["objects"], dtype=np.float32)
        if "privileged" in observation and self.allow_privileged:
            message["privileged"] = privileged_message(observation["privileged"])
        reply = self._call(message)
        if "actions" not in reply:
            raise PolicyServerError(f"the policy server's reply has no 'actions' (keys: "
                                    f"{server_text(sorted(map(str, reply)))})")
        return reply["actions"]  # checked by the episode (validate_actions)

    def close(self) -> None:
        if self.connection is not None:
            self.exits.close()
            self.connection = None
