"""Policies behind the openpi websocket protocol: the client the harness uses and
`robofollow serve`, which puts any Python policy behind it.

Protocol (openpi's): on connect the server sends its metadata (a msgpack map); then each
client message is an observation and each reply a map with "actions" ([H, 14]). Messages are
msgpack with numpy arrays (robofollow.eval.wire). Observations follow openpi's ALOHA
convention: "state" (float32 [14]), "images" {cam_high, cam_left_wrist, cam_right_wrist} as
uint8 [3, H, W], "prompt" (the instruction). A server that fails sends its traceback as a text
message and closes.

Extensions only between RoboFollow ends (an openpi server never sees them): a server whose
metadata carries "robofollow" accepts {"reset": true} at an episode start, declares the
observation parts its policy uses, and for a privileged (reference) policy receives
"privileged" = {scene, layout, seed}, from which it rebuilds the same start state itself.
"""

from __future__ import annotations

import traceback
from contextlib import ExitStack

import numpy as np
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect
from websockets.sync.server import serve

from robofollow.build import Compiled
from robofollow.errors import RoboFollowError
from robofollow.eval.policy import OBSERVATION_PARTS, PolicyConnectionError
from robofollow.eval.serving import ServedPolicy, privileged_message
from robofollow.eval.wire import packb, unpackb
from robofollow.sim.cameras import CAMERA_NAMES

OPENPI_USES = frozenset({"state", "instruction", "images"})


class WebsocketPolicy:
    """A policy served over the openpi websocket protocol (`ws://host:port`)."""

    def __init__(self, uri: str, timeout: float = 60.0, retries: int = 3):
        self.uri, self.timeout, self.retries = uri, timeout, retries
        self.connection = None
        self.metadata = self._connect()
        declared = self.metadata.get("robofollow", {}).get("uses")
        self.uses = (frozenset(declared) & OBSERVATION_PARTS if declared is not None
                     else OPENPI_USES)

    def _connect(self) -> dict:
        self.close()
        try:
            self.exits = ExitStack()
            self.connection = self.exits.enter_context(connect(
                self.uri, compression=None, max_size=None, open_timeout=self.timeout))
            metadata = unpackb(self.connection.recv(timeout=self.timeout))
        except (OSError, TimeoutError, ConnectionClosed) as error:
            raise PolicyConnectionError(f"cannot reach the policy server at {self.uri}: "
                                        f"{error}") from None
        return metadata if isinstance(metadata, dict) else {}

    def _call(self, message: dict) -> dict:
        """Send one message and return the reply, reconnecting on a lost connection or a
        time-out (up to `retries` times)."""
        for attempt in range(self.retries + 1):
            try:
                if self.connection is None:
                    self._connect()
                self.connection.send(packb(message))
                reply = self.connection.recv(timeout=self.timeout)
            except (OSError, TimeoutError, ConnectionClosed, PolicyConnectionError) as error:
                self.close()
                if attempt == self.retries:
                    raise PolicyConnectionError(
                        f"the policy server at {self.uri} did not answer after "
                        f"{self.retries + 1} tries: {type(error).__name__}: {error}") from None
                continue
            if isinstance(reply, str):  # the server's traceback
                raise RoboFollowError(f"the policy server failed: {reply.strip()}")
            return unpackb(reply)
        raise AssertionError("unreachable")

    def reset(self) -> None:
        if "robofollow" in self.metadata:
            self._call({"reset": True})

    def act(self, observation: dict) -> np.ndarray:
        message = {"state": np.asarray(observation["state"], dtype=np.float32),
                   "prompt": observation.get("instruction", "")}
        if "images" in observation:
            message["images"] = {camera: np.ascontiguousarray(image.transpose(2, 0, 1))
                                 for camera, image in observation["images"].items()}
        if "privileged" in observation:
            message["privileged"] = privileged_message(observation["privileged"])
        reply = self._call(message)
        if "actions" not in reply:
            raise RoboFollowError(f"the policy server's reply has no 'actions' "
                                  f"(keys: {sorted(reply)})")
        return np.asarray(reply["actions"])

    def close(self) -> None:
        if self.connection is not None:
            self.exits.close()
            self.connection = None


class PolicyServer:
    """Serves one Python policy; one client at a time is the expected use."""

    def __init__(self, compiled: Compiled, policy_spec: str):
        self.served = ServedPolicy(compiled, policy_spec)

    def handle(self, connection) -> None:
        connection.send(packb(self.served.metadata))
        try:
            for data in connection:
                message = unpackb(data)
                if message.get("reset"):
                    self.served.reset()
                    connection.send(packb({"reset": True}))
                    continue
                images = ({camera: np.ascontiguousarray(message["images"][camera]
                                                        .transpose(1, 2, 0))
                           for camera in CAMERA_NAMES if camera in message["images"]}
                          if "images" in message else None)
                actions = self.served.act(message["state"], message.get("prompt", ""), images,
                                          message.get("privileged"), message.get("step", 0))
                connection.send(packb({"actions": actions}))
        except ConnectionClosed:
            return
        except Exception:  # the client gets the traceback, as openpi servers do
            connection.send(traceback.format_exc())
            connection.close()

    def serve_forever(self, host: str, port: int, ready=None) -> None:
        with serve(self.handle, host, port, compression=None, max_size=None) as server:
            if ready is not None:
                ready(server)
            server.serve_forever()
