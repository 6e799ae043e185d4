"""A Python policy behind a server, whatever the protocol: it turns the wire's observations
back into the harness's and, for a privileged (reference) policy, rebuilds the episode's start
from {scene, layout, seed} (deterministic, so it sees what the client's simulation holds; a
RoboFollow client sends them only when its user allowed it).

Servers listen on 127.0.0.1 unless told otherwise, serve each connection in its own thread
with its own policy instance (a pool of at most `max_clients`, reused by later connections),
close a connection idle for `idle_timeout` seconds, refuse messages over `max_message` bytes
and answer a failed request with its error message only: the traceback goes to the server's
log (stderr), never to the client."""

from __future__ import annotations

import logging
import threading
from importlib.metadata import version

import numpy as np

from robofollow.build import Compiled
from robofollow.errors import RoboFollowError
from robofollow.eval.loading import load_policy
from robofollow.eval.policy import Privileged, server_text
from robofollow.eval.wire import MAX_MESSAGE_BYTES
from robofollow.sim.stage import Stage

DEFAULT_HOST = "127.0.0.1"  # this machine only; 0.0.0.0 exposes a server to the network
IDLE_TIMEOUT_S = 300.0  # a connection that sends nothing for this long is closed
MAX_CLIENTS = 8  # connections served at once, each with its own policy instance

log = logging.getLogger("robofollow.serve")


class RequestError(ValueError):
    """A client's message that is not a request of the protocol."""


class ServerBusyError(RoboFollowError):
    """Every policy instance of the server is in use."""


class ServerLimits:
    """What a server accepts: message size (bytes), idle time (s) and clients at once (None:
    the default)."""

    def __init__(self, max_message: int | None = None, idle_timeout: float | None = None,
                 max_clients: int | None = None):
        self.max_message = MAX_MESSAGE_BYTES if max_message is None else max_message
        self.idle_timeout = IDLE_TIMEOUT_S if idle_timeout is None else idle_timeout
        self.max_clients = MAX_CLIENTS if max_clients is None else max_clients
        if self.max_message < 1 or not self.idle_timeout > 0 or self.max_clients < 1:
            raise ValueError("server limits must be positive")


class ServedPolicy:
    def __init__(self, compiled: Compiled, policy_spec: str):
        self.compiled, self.policy, self.spec = compiled, load_policy(policy_spec), policy_spec
        self.stage = Stage()
        self.start: tuple | None = None
        self.privileged: Privileged | None = None

    @property
    def metadata(self) -> dict:
        """What a RoboFollow client learns of the server: version and the parts used."""
        return {"robofollow": {"version": version("robofollow"),
                               "uses": sorted(self.policy.uses)}, "policy": self.spec}

    def reset(self) -> None:
        self.policy.reset()
        self.start = None

    def act(self, state, instruction: str, images: dict | None, privileged: dict | None,
            step: int = 0) -> np.ndarray:
        """`images`: {camera: (H, W, 3) uint8}; `privileged`: {scene, layout, seed}."""
        try:
            state = np.asarray(state)
        except (TypeError, ValueError):
            raise RequestError("'state' is not numbers") from None
        if state.dtype.kind not in "fiu":
            raise RequestError("'state' is not numbers")
        state = state.astype(np.float32)
        if state.shape != (14,):
            raise RequestError(f"'state' must be 14 numbers, got shape {list(state.shape)}")
        if not isinstance(instruction, str):
            raise RequestError("the instruction is not a string")
        if not isinstance(step, int) or isinstance(step, bool):
            raise RequestError("'step' is not an integer")
        obs = {"state": state, "instruction": instruction, "step": step}
        if images is not None:
            obs["images"] = images
        if "privileged" in self.policy.uses:
            if privileged is None:
                raise RequestError(
                    f"policy {self.spec!r} needs privileged observations (the episode's scene, "
                    "layout and seed) and the client sent none: evaluate it with "
                    "`robofollow eval --allow-privileged`")
            obs["privileged"] = self._privileged(privileged)
        return np.asarray(self.policy.act(obs), dtype=np.float32)

    def _privileged(self, message) -> Privileged:
        if not isinstance(message, dict):
            raise RequestError("'privileged' must be {scene, layout, seed}")
        start = (message.get("scene"), message.get("layout"), message.get("seed"))
        if start != self.start:
            scenes = self.compiled.spec.scenes
            if not isinstance(start[0], str) or start[0] not in scenes:
                raise RequestError(f"'privileged' names no known scene: "
                                   f"{server_text(repr(start[0]))}")
            if not isinstance(start[2], int) or isinstance(start[2], bool):
                raise RequestError("'privileged' seed is not an integer")
            scene = scenes[start[0]]
            try:
                sim = self.stage.simulation(scene, start[1])
            except (KeyError, TypeError, ValueError, RoboFollowError):
                raise RequestError(f"scene {start[0]} has no layout "
                                   f"{server_text(repr(start[1]))}") from None
            world = sim.reset(start[2])
            self.privileged = Privileged(sim, world, scene, self.compiled.candidates(scene.id),
                                         start[2])
            self.start = start
        return self.privileged

    def close(self) -> None:
        self.stage.close()


class PolicyPool:
    """Policy instances for concurrent connections: one is loaded now (a bad --policy fails
    before the server listens), more as connections need them, at most `size`; a
    connection's instance is reset and kept for later connections."""

    def __init__(self, compiled: Compiled, policy_spec: str, size: int = MAX_CLIENTS):
        self.compiled, self.spec, self.size = compiled, policy_spec, size
        self.idle = [ServedPolicy(compiled, policy_spec)]
        self.metadata = self.idle[0].metadata  # the same for every instance
        self.count = 1
        self.lock = threading.Lock()

    def acquire(self) -> ServedPolicy:
        with self.lock:
            if self.idle:
                return self.idle.pop()
            if self.count >= self.size:
                raise ServerBusyError(f"the server is serving its limit of {self.size} "
                                      "clients; try again later")
            self.count += 1
        try:
            return ServedPolicy(self.compiled, self.spec)
        except BaseException:
            with self.lock:
                self.count -= 1
            raise

    def release(self, served: ServedPolicy) -> None:
        try:
            served.reset()
        except Exception:  # a policy that cannot reset is not handed to the next client
            log.exception("policy %s failed to reset; dropped", self.spec)
            with self.lock:
                self.count -= 1
            served.close()
            return
        with self.lock:
            self.idle.append(served)

    def close(self) -> None:
        with self.lock:
            idle, self.idle = self.idle, []
        for served in idle:
            served.close()


def error_reply(error: Exception, where: str) -> str:
    """What a client is told of a failed request: the error's type and message only. The
    traceback is logged here (a bad request is logged without one)."""
    if isinstance(error, RequestError | ServerBusyError):
        log.warning("%s: %s", where, error)
    else:
        log.error("%s: the policy failed", where, exc_info=error)
    return server_text(f"{type(error).__name__}: {error}")


def privileged_message(privileged: Privileged) -> dict:
    """The start a served reference policy rebuilds: {scene, layout, seed}."""
    return {"scene": privileged.scene.id, "layout": privileged.sim.layout,
            "seed": privileged.seed}
