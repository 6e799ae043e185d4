"""What a --policy names: a reference policy, a shipped baseline (`baseline:NAME`), a baseline
checkpoint folder, a policy server (`ws://` or `wss://`, `tcp://`), or else `module:factory`."""

from __future__ import annotations

from typing import Literal

from robofollow.eval.policies.reference import REFERENCE_POLICIES

PolicyKind = Literal["reference", "baseline", "checkpoint", "factory", "ws", "tcp"]
SERVER_KINDS = ("ws", "tcp")


def policy_kind(spec: str) -> PolicyKind:
    """The kind of policy a --policy names; "factory" for any other (loading checks it)."""
    if spec in REFERENCE_POLICIES:
        return "reference"
    if spec.startswith(("ws://", "wss://")):
        return "ws"
    if spec.startswith("tcp://"):
        return "tcp"
    from robofollow.learn import checkpoint  # only where a checkpoint may be named

    if spec.startswith(checkpoint.PREFIX):
        return "baseline"
    if checkpoint.is_checkpoint(spec):
        return "checkpoint"
    return "factory"


def is_server(spec: str) -> bool:
    """Whether a --policy names a policy server rather than an in-process policy."""
    return policy_kind(spec) in SERVER_KINDS


def is_trained(spec: str) -> bool:
    """Whether a --policy names a trained baseline (whose JAX version a run's provenance
    names)."""
    return policy_kind(spec) in ("baseline", "checkpoint")
