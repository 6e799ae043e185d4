"""Turning a --policy argument into a policy: a reference policy's name, a shipped baseline
(`baseline:NAME`), a baseline checkpoint folder, `module:factory` (a callable returning a
policy, imported from the Python path), `ws://host:port` (a server speaking openpi's websocket
protocol) or `tcp://host:port` (upstream RoboFollow's protocol)."""

from __future__ import annotations

import importlib
import importlib.util
import math
from urllib.parse import parse_qsl, urlsplit

from robofollow.errors import RoboFollowError, UsageError, did_you_mean
from robofollow.eval.policies.policy import OBSERVATION_PARTS, Policy
from robofollow.eval.policies.policy_kind import (
    SERVER_KINDS,
    PolicyKind,
    is_server,
    policy_kind,
)
from robofollow.eval.policies.reference import REFERENCE_POLICIES
from robofollow.eval.policies.tcp_client import TcpPolicy
from robofollow.eval.policies.websocket_client import WebsocketPolicy


class PolicyLoadError(RoboFollowError):
    """A --policy that names nothing usable."""


def load_policy(spec: str) -> Policy:
    kind = policy_kind(spec)
    if kind == "reference":
        return REFERENCE_POLICIES[spec]()
    if kind in SERVER_KINDS:
        return _remote(spec, kind)
    if kind in ("baseline", "checkpoint"):
        from robofollow.learn.policy import (
            load_baseline,  # (the learn package is heavy)
        )

        return load_baseline(spec)
    module_name, factory_name = _factory_parts(spec)
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


def check_policy(spec: str) -> None:
    """Said before anything runs, without building the policy or reaching its server: a
    --policy that names nothing usable (a misspelt reference policy or shipped baseline, with
    the closest name; a malformed server address; a module that cannot be found)."""
    kind = policy_kind(spec)
    if kind in SERVER_KINDS:
        _server_settings(spec)
    elif kind == "baseline":
        from robofollow.learn.policy import (
            shipped_folder,  # (the learn package is heavy)
        )

        shipped_folder(spec)
    elif kind == "factory":
        module_name, _ = _factory_parts(spec)
        try:
            found = importlib.util.find_spec(module_name)
        except (ImportError, ValueError) as error:
            raise PolicyLoadError(f"--policy {spec!r}: cannot import {module_name}: "
                                  f"{error}") from None
        if found is None:
            raise PolicyLoadError(f"--policy {spec!r}: no module {module_name!r} on the "
                                  "Python path")


def _factory_parts(spec: str) -> tuple[str, str]:
    """A `module:factory` policy's module and factory; else the error, with the closest
    reference policy where the name is one misspelt ("did you mean 'blind'?")."""
    module_name, _, factory_name = spec.partition(":")
    if module_name and factory_name:
        return module_name, factory_name
    hint = did_you_mean(spec.lower(), REFERENCE_POLICIES)
    raise PolicyLoadError(f"--policy {spec!r}: {hint + ' ' if hint else ''}expected one of "
                          f"{', '.join(REFERENCE_POLICIES)}, baseline:NAME, a checkpoint "
                          "folder, module:factory, ws://host:port or tcp://host:port")


SERVER_SETTINGS = {"timeout": float, "retries": int, "max_message": int, "privileged": int}


def _remote(spec: str, kind: PolicyKind) -> Policy:
    """A policy server: `ws://` or `tcp://` HOST:PORT, optionally
    `?timeout=S&retries=N&max_message=BYTES&privileged=1`: seconds per call before a retry
    (default 60); retries after a time-out or a lost connection (default 3); the largest
    message accepted from the server (default limits.MAX_MESSAGE_BYTES, 16 MiB); whether the
    server may have privileged observations, each episode's scene, layout and seed (default 0:
    a server that asks for them is refused; `robofollow eval --allow-privileged` adds it, and
    the run's policy records it)."""
    address, settings = _server_settings(spec)
    if kind == "tcp":
        return TcpPolicy(address.hostname, address.port, **settings)
    return WebsocketPolicy(f"{address.scheme}://{address.netloc}{address.path}", **settings)


def _server_settings(spec: str):
    """A server --policy's address (urlsplit) and its settings, checked."""
    address = urlsplit(spec)
    try:
        pairs = parse_qsl(address.query, strict_parsing=bool(address.query))
        settings = {key: SERVER_SETTINGS[key](value) for key, value in pairs
                    if key in SERVER_SETTINGS}
        port = address.port
    except ValueError as error:
        raise PolicyLoadError(f"--policy {spec!r}: {error}") from None
    if ({key for key, _ in pairs} - set(SERVER_SETTINGS) or not address.hostname
            or port is None):
        raise PolicyLoadError(f"--policy {spec!r}: expected {address.scheme}://HOST:PORT "
                              "with optional ?timeout=SECONDS&retries=N&max_message=BYTES"
                              "&privileged=1")
    timeout = settings.get("timeout", 1)
    if (not (math.isfinite(timeout) and timeout > 0) or settings.get("retries", 0) < 0
            or settings.get("max_message", 1) < 1 or settings.get("privileged", 0) not in (0, 1)):
        raise PolicyLoadError(f"--policy {spec!r}: timeout must be a finite number of seconds "
                              "above 0, max_message positive, retries at least 0, privileged "
                              "0 or 1")
    settings["privileged"] = bool(settings.get("privileged", 0))
    return address, settings


def with_privileged(spec: str) -> str:
    """A server's --policy with privileged observations allowed (`?privileged=1`), as
    `robofollow eval --allow-privileged` gives it: the run's options record it."""
    if not is_server(spec):
        raise UsageError(f"--allow-privileged is for policy servers (ws:// or tcp://); "
                         f"{spec!r} runs in this process")
    address = urlsplit(spec)
    pairs = [(key, value) for key, value in parse_qsl(address.query) if key != "privileged"]
    query = "&".join(f"{key}={value}" for key, value in [*pairs, ("privileged", "1")])
    return address._replace(query=query).geturl()
