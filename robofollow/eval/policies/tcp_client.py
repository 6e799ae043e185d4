"""The client of upstream RoboFollow's TCP protocol (protocols/tcp_protocol.py): a policy served
at `tcp://host:port`. A reply over the client's limit fails the call."""

from __future__ import annotations

import socket

import numpy as np

from robofollow.eval.policies.policy import (
    PolicyConnectionError,
    PolicyServerError,
    declared_uses,
    privileged_message,
)
from robofollow.eval.protocols.limits import CALL_TIMEOUT_S, MAX_MESSAGE_BYTES
from robofollow.eval.protocols.tcp_protocol import (
    CAMERAS,
    receive_message,
    send_message,
)
from robofollow.eval.protocols.wire import MessageTooBig, WireError, server_text

UPSTREAM_USES = frozenset({"state", "instruction", "images"})


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
        if "objects" in observation:
            obs["objects"] = np.asarray(observation["objects"], dtype=np.float32)
        if "privileged" in observation and self.allow_privileged:
            obs["privileged"] = privileged_message(observation["privileged"])
        return self._call("predict", obs)  # checked by the episode (validate_actions)

    def close(self) -> None:
        if self.connection is not None:
            self.connection.close()
            self.connection = None
