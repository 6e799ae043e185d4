"""Policies behind the openpi websocket protocol: the client the harness uses and
`robofollow serve`, which puts any Python policy behind it.

Protocol (openpi's): on connect the server sends its metadata (a msgpack map); then each
client message is an observation and each reply a map with "actions" ([H, 14]). Messages are
msgpack with numpy arrays (robofollow.eval.wire). Observations follow openpi's ALOHA
convention: "state" (float32 [14]), "images" {cam_high, cam_left_wrist, cam_right_wrist} as
uint8 [3, H, W], "prompt" (the instruction). A server that fails sends a text message and
closes; `robofollow serve` sends the error's type and message only (the traceback goes to its
log). Either end closes the connection (code 1009) on a message over its size limit
(`robofollow.eval.limits.MAX_MESSAGE_BYTES` unless configured); the client then fails the call
with the reason, without retrying.

`robofollow serve` also answers `GET /healthz` with 200 (as openpi's server does), checks each
observation against the layout its metadata declares ("robofollow": {"observation": ...}),
and resets its policy for each connection.

Extensions only between RoboFollow ends (an openpi server never sees them): a server whose
metadata carries "robofollow" accepts {"reset": true} at an episode start, receives "step"
(control steps executed so far) with each observation, declares the observation parts its
policy uses, and for a privileged (reference) policy receives "privileged" = {scene, layout,
seed}, from which it rebuilds the same start state itself, where the user allowed it
(`robofollow eval --allow-privileged`). Any client may send "step"; a step of 0 after others
begins a new episode.
"""

from __future__ import annotations

import http
from contextlib import ExitStack

import numpy as np
from websockets.exceptions import ConnectionClosed, InvalidURI, WebSocketException
from websockets.frames import CloseCode
from websockets.sync.client import connect
from websockets.sync.server import serve

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
    ServerLimits,
    checked_images,
    error_reply,
    log,
    privileged_message,
)
from robofollow.eval.wire import WireError, packb, size_text, unpackb

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


def _health(connection, request):
    """`GET /healthz` is answered 200 without a websocket handshake; other paths go on."""
    if request.path == "/healthz":
        return connection.respond(http.HTTPStatus.OK, "OK\n")
    return None


class PolicyServer:
    """Serves one Python policy; each connection in its own thread with its own policy
    instance, at most `limits.max_clients` at once."""

    def __init__(self, compiled: Compiled, policy_spec: str,
                 limits: ServerLimits | None = None):
        self.limits = limits or ServerLimits()
        self.pool = PolicyPool(compiled, policy_spec, self.limits.max_clients)
        self.server = None

    def handle(self, connection) -> None:
        peer = str(getattr(connection, "remote_address", "client"))
        try:
            served = self.pool.acquire()
        except Exception as error:  # busy
            self._fail(connection, error_reply(error, peer))
            return
        try:
            connection.send(packb(self.pool.metadata(channels_first=True)))
            while True:
                try:
                    data = connection.recv(timeout=self.limits.idle_timeout)
                except TimeoutError:
                    log.warning("%s: idle for %s s; closed", peer, self.limits.idle_timeout)
                    connection.close(CloseCode.GOING_AWAY, "idle")
                    return
                try:
                    message = unpackb(data)
                    if not isinstance(message, dict):
                        raise RequestError("an observation must be a map")
                    if message.get("reset"):
                        served.reset()
                        connection.send(packb({"reset": True}))
                        continue
                    if "state" not in message:
                        raise RequestError("the observation has no 'state'")
                    images = message.get("images")
                    if images is not None and "images" in self.pool.uses:
                        images = checked_images(images, channels_first=True)
                    actions = served.act(message["state"], message.get("prompt", ""), images,
                                         message.get("privileged"), message.get("step"))
                    reply = packb({"actions": actions})
                except Exception as error:  # openpi's way: a text message, then close
                    if isinstance(error, WireError):
                        error = RequestError(str(error))
                    self._fail(connection, error_reply(error, peer))
                    return
                connection.send(reply)
        except ConnectionClosed:  # the client left, or sent a message over the limit
            return
        except Exception:  # never the server: only this connection ends
            log.exception("%s: connection failed", peer)
        finally:
            self.pool.release(served)

    @staticmethod
    def _fail(connection, text: str) -> None:
        try:
            connection.send(text)
            connection.close(CloseCode.INTERNAL_ERROR, "error")
        except ConnectionClosed:
            pass

    def serve_forever(self, host: str = DEFAULT_HOST, port: int = 0, ready=None) -> None:
        with serve(self.handle, host, port, compression=None, max_size=self.limits.max_message,
                   open_timeout=min(10.0, self.limits.idle_timeout),
                   process_request=_health) as server:
            self.server = server
            if ready is not None:
                ready(server)
            server.serve_forever()

    def shutdown(self) -> None:
        if self.server is not None:
            self.server.shutdown()
