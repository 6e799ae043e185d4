"""A Python policy behind a server, whatever the protocol: it turns the wire's observations
back into the harness's and, for a privileged (reference) policy, rebuilds the episode's start
from {scene, layout, seed} (deterministic, so it sees what the client's simulation holds; a
RoboFollow client sends them only when its user allowed it).

Servers listen on 127.0.0.1 unless told otherwise, serve each connection in its own thread
with its own policy instance (a pool of at most `max_clients`, reused by later connections),
close a connection idle for `idle_timeout` seconds, refuse messages over `max_message` bytes
and answer a failed request with its error message only: the traceback goes to the server's
log (stderr), never to the client.

A policy is reset when a connection takes it, when a RoboFollow client says an episode begins
and when an observation's "step" is 0 after the policy has acted (openpi's clients send no
episode boundary: they may send "step", or open a connection per episode). Observations are
checked against the layout the server declares in its metadata (`observation_layout`) and
refused with an error reply that says what was expected; so are NaN, infinite numbers and
numbers beyond MAX_OBSERVATION_MAGNITUDE. So are a policy's actions before they are sent: ones
that are not finite float32 [T, 14] numbers get an error reply instead."""

from __future__ import annotations

import logging
import threading
from importlib.metadata import version

import numpy as np

from robofollow.benchmark.episode import Benchmark
from robofollow.errors import RoboFollowError
from robofollow.eval.policies.loading import load_policy
from robofollow.eval.policies.policy import (
    ACTION_WIDTH,
    BadActionError,
    Privileged,
    validate_actions,
)
from robofollow.eval.protocols.limits import (
    IDLE_TIMEOUT_S,
    MAX_CLIENTS,
    MAX_MESSAGE_BYTES,
    MAX_OBSERVATION_MAGNITUDE,
)
from robofollow.eval.protocols.wire import server_text
from robofollow.sim.cameras import CAMERA_NAMES, IMAGE_HEIGHT, IMAGE_WIDTH
from robofollow.sim.objects import FIELDS, SHAPE
from robofollow.sim.stage import Stage

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


def image_shape(channels_first: bool) -> list[int]:
    """The shape of a camera image on the wire: [3, H, W] (openpi) or [H, W, 3] (upstream)."""
    return [3, IMAGE_HEIGHT, IMAGE_WIDTH] if channels_first else [IMAGE_HEIGHT, IMAGE_WIDTH, 3]


def observation_layout(uses: frozenset, channels_first: bool) -> dict:
    """The observation a server's policy reads, as declared in its metadata."""
    layout = {"state": {"dtype": "float32", "shape": [ACTION_WIDTH]},
              "instruction": {"dtype": "str"}, "step": {"dtype": "int", "optional": True}}
    if "images" in uses:
        layout["images"] = {camera: {"dtype": "uint8", "shape": image_shape(channels_first)}
                            for camera in CAMERA_NAMES}
    if "objects" in uses:
        layout["objects"] = {"dtype": "float32", "shape": list(SHAPE), "fields": list(FIELDS)}
    return layout


def _shape_text(value) -> str:
    return f"{value.dtype} {list(value.shape)}" if isinstance(value, np.ndarray) else \
        f"a {type(value).__name__}"


def checked_images(images, channels_first: bool, names: dict[str, str] | None = None,
                   where: str = "'images'") -> dict[str, np.ndarray]:
    """The three cameras' images as (H, W, 3) uint8, from a message's {camera: array} in the
    protocol's layout (`names`: the protocol's name of each camera; `where`: the message part
    holding them); RequestError says what was expected where an image is missing or of
    another shape or type (channels in the other place, a batch axis, floats...)."""
    names = names or {camera: camera for camera in CAMERA_NAMES}
    if not isinstance(images, dict):
        raise RequestError(f"{where} must map {', '.join(names.values())} to images")
    expected = image_shape(channels_first)
    order = "channels first, openpi's convention" if channels_first else \
        "height, width, channels: upstream's convention"
    checked = {}
    for camera in CAMERA_NAMES:
        image = images.get(camera)
        if image is None:
            raise RequestError(f"{where} has no {names[camera]!r} (the policy reads "
                               f"{', '.join(names.values())})")
        if not (isinstance(image, np.ndarray) and image.dtype == np.uint8
                and list(image.shape) == expected):
            raise RequestError(f"image {names[camera]!r} must be uint8 {expected} ({order}); "
                               f"got {_shape_text(image)}")
        checked[camera] = np.ascontiguousarray(image.transpose(1, 2, 0)) if channels_first \
            else image
    return checked


def _checked_objects(objects, spec: str) -> np.ndarray:
    if objects is None:
        raise RequestError(f"policy {spec!r} reads the objects observation and the "
                           "observation has none ('objects')")
    if not (isinstance(objects, np.ndarray) and objects.dtype == np.float32
            and objects.shape == SHAPE):
        raise RequestError(f"'objects' must be float32 {list(SHAPE)} (one row per body: "
                           f"{', '.join(FIELDS)}); got {_shape_text(objects)}")
    return _physical(objects, "'objects'")


def _physical(values: np.ndarray, name: str) -> np.ndarray:
    """`values` (float32), refused where one is NaN, infinite (a number beyond float32's range
    included: the cast made it infinite) or beyond MAX_OBSERVATION_MAGNITUDE."""
    bad = np.argwhere(~(np.abs(values) <= MAX_OBSERVATION_MAGNITUDE))  # NaN compares False
    if len(bad):
        raise RequestError(f"{name} must be finite numbers of magnitude at most "
                           f"{MAX_OBSERVATION_MAGNITUDE:g}; got {values[tuple(bad[0])]:g} at "
                           f"{bad[0].tolist()}")
    return values


def checked_actions(actions) -> np.ndarray:
    """A policy's chunk as a server sends it: float32 [T, 14]. BadActionError says what is
    wrong with one that is not real finite numbers of that shape (`validate_actions`), as
    float32 too (a number beyond its range would arrive infinite)."""
    try:
        validate_actions(actions)
        with np.errstate(over="ignore"):
            chunk = np.asarray(actions, dtype=np.float32).reshape(-1, ACTION_WIDTH)
        validate_actions(chunk)
    except BadActionError as error:
        raise BadActionError("the policy returned actions the protocol cannot carry: "
                             f"{error}") from None
    return chunk


class ServedPolicy:
    """One policy instance behind a server, with the observation checks and episode
    boundaries of the serving protocol."""

    def __init__(self, compiled: Benchmark, policy_spec: str):
        self.compiled, self.policy, self.spec = compiled, load_policy(policy_spec), policy_spec
        self.stage = Stage()
        self.start: tuple | None = None
        self.privileged: Privileged | None = None
        self.acted = False  # since the last reset

    def metadata(self, channels_first: bool) -> dict:
        """What a client learns of the server: version, the parts used and their layout."""
        return {"robofollow": {
            "version": version("robofollow"), "uses": sorted(self.policy.uses),
            "observation": observation_layout(self.policy.uses, channels_first)},
            "policy": self.spec}

    def reset(self) -> None:
        self.policy.reset()
        self.start, self.acted = None, False

    def act(self, state, instruction: str, images: dict | None, privileged: dict | None,
            step: int | None = None, objects=None) -> np.ndarray:
        """`images`: {camera: (H, W, 3) uint8}, checked (`checked_images`); `privileged`:
        {scene, layout, seed}; `step`: control steps executed so far, None when the client
        does not say (a step of 0 begins a new episode); `objects`: the objects observation
        (float32 objects.SHAPE)."""
        state = _checked_state(state)
        if not isinstance(instruction, str):
            raise RequestError("the instruction ('prompt') must be a string")
        if step is not None and (not isinstance(step, int) or isinstance(step, bool)
                                 or step < 0):
            raise RequestError("'step' must be a whole number of control steps")
        if step == 0 and self.acted:  # a new episode on the same connection
            self.reset()
        obs = {"state": state, "instruction": instruction}
        if step is not None:
            obs["step"] = step
        if "images" in self.policy.uses:
            if images is None:
                raise RequestError(f"policy {self.spec!r} reads the camera images and the "
                                   "observation has none")
            obs["images"] = images
        if "objects" in self.policy.uses:
            obs["objects"] = _checked_objects(objects, self.spec)
        if "privileged" in self.policy.uses:
            if privileged is None:
                raise RequestError(
                    f"policy {self.spec!r} is a reference policy that reads privileged "
                    "observations (the episode's scene, layout and seed, to rebuild the "
                    "simulation's ground truth); only a RoboFollow client sends them, with "
                    "`robofollow eval --allow-privileged`. Other clients (openpi's) cannot "
                    "drive it: serve a policy that reads state, instruction and images")
            obs["privileged"] = self._privileged(privileged)
        self.acted = True
        return checked_actions(self.policy.act(obs))

    def _privileged(self, message) -> Privileged:
        """The episode's start, rebuilt when {scene, layout, seed} changes."""
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


def _checked_state(state) -> np.ndarray:
    try:
        state = np.asarray(state)
    except (TypeError, ValueError):
        raise RequestError("'state' is not numbers") from None
    if state.dtype.kind not in "fiu":
        raise RequestError("'state' is not numbers")
    if state.shape != (ACTION_WIDTH,):
        raise RequestError(f"'state' must be {ACTION_WIDTH} numbers (shape [{ACTION_WIDTH}], "
                           f"no batch axis), got shape {list(state.shape)}")
    with np.errstate(over="ignore"):  # a number beyond float32's range: infinite, refused
        return _physical(state.astype(np.float32), "'state'")


class PolicyPool:
    """Policy instances for concurrent connections: one is loaded now (a bad --policy fails
    before the server listens), more as connections need them, at most `size`; a
    connection's instance is reset and kept for later connections."""

    def __init__(self, compiled: Benchmark, policy_spec: str, size: int = MAX_CLIENTS):
        self.compiled, self.spec, self.size = compiled, policy_spec, size
        self.idle = [ServedPolicy(compiled, policy_spec)]
        self.metadata = self.idle[0].metadata  # the same for every instance
        self.uses = self.idle[0].policy.uses
        self.count = 1
        self.lock = threading.Lock()

    def acquire(self) -> ServedPolicy:
        """An instance for a new connection, as at an episode's start."""
        with self.lock:
            if self.idle:
                return self.idle.pop()  # reset on release
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
    traceback is logged here (a bad request or bad actions are logged without one)."""
    if isinstance(error, RequestError | ServerBusyError | BadActionError):
        log.warning("%s: %s", where, error)
    else:
        log.error("%s: the policy failed", where, exc_info=error)
    return server_text(f"{type(error).__name__}: {error}")
