"""Turning a --policy argument into a policy: a reference policy's name, a shipped baseline
(`baseline:NAME`), a baseline checkpoint folder, `module:factory` (a callable returning a
policy, imported from the Python path), `ws://host:port` (a server speaking openpi's websocket
protocol) or `tcp://host:port` (upstream RoboFollow's protocol)."""

from __future__ import annotations

import importlib
from urllib.parse import parse_qsl, urlsplit

from robofollow.errors import RoboFollowError
from robofollow.eval.policy import OBSERVATION_PARTS, Policy
from robofollow.eval.reference import REFERENCE_POLICIES


class PolicyLoadError(RoboFollowError):
    """A --policy that names nothing usable."""


def is_server(spec: str) -> bool:
    """Whether a --policy names a policy server rather than an in-process policy."""
    return spec.startswith(("ws://", "wss://", "tcp://"))


def load_policy(spec: str) -> Policy:
    if spec in REFERENCE_POLICIES:
        return REFERENCE_POLICIES[spec]()
    if is_server(spec):
        return _remote(spec)
    from robofollow.learn import checkpoint, policy as baseline

    if spec.startswith(baseline.PREFIX) or checkpoint.is_checkpoint(spec):
        return baseline.load_baseline(spec)
    module_name, _, factory_name = spec.partition(":")
    if not module_name or not factory_name:
        raise PolicyLoadError(f"--policy {spec!r}: expected one of "
                              f"{', '.join(REFERENCE_POLICIES)}, baseline:NAME, a checkpoint "
                              "folder, module:factory, ws://host:port or tcp://host:port")
    try:
        module = importlib.import_module(module_name)
    except ImportError as error:
        raise PolicyLoadError(f"--policy {spec!r}: cannot import {module_name}: {error}") from None
    factory = getattr(module, factory_name, None)
    if not callable(factory):
        raise PolicyLoadError(f"--policy {spec!r}: {module_name} has no callable "
                              f"{factory_name!r}")
    policy = factory()
    missing = [name for name in ("reset", "act") if not callable(getattr(policy, name, None))]
    uses = getattr(policy, "uses", None)
    if missing or not isinstance(uses, frozenset | set) or not set(uses) <= OBSERVATION_PARTS:
        raise PolicyLoadError(
            f"--policy {spec!r}: the factory's object is not a policy (it needs reset(), "
            f"act(observation) and uses, a set of {sorted(OBSERVATION_PARTS)})")
    return policy


def _remote(spec: str) -> Policy:
    """A policy server: `ws://` or `tcp://` HOST:PORT, optionally `?timeout=S&retries=N`
    (seconds per call before a retry, default 60; retries after a time-out or a lost
    connection, default 3)."""
    address = urlsplit(spec)
    try:
        settings = {key: float(value) if key == "timeout" else int(value)
                    for key, value in parse_qsl(address.query,
                                                strict_parsing=bool(address.query))}
        port = address.port
    except ValueError as error:
        raise PolicyLoadError(f"--policy {spec!r}: {error}") from None
    if set(settings) - {"timeout", "retries"} or not address.hostname or port is None:
        raise PolicyLoadError(f"--policy {spec!r}: expected {address.scheme}://HOST:PORT "
                              "with optional ?timeout=SECONDS&retries=N")
    if address.scheme == "tcp":
        from robofollow.eval.tcp import TcpPolicy

        return TcpPolicy(address.hostname, port, **settings)
    from robofollow.eval.websocket import WebsocketPolicy  # (it serves loaded policies)

    return WebsocketPolicy(f"{address.scheme}://{address.netloc}{address.path}", **settings)
