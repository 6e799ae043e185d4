"""A compiled benchmark (the spec, its splits, the training behaviours and the audit) and how
the parts its scenes compile to make one."""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property
from types import MappingProxyType

from robofollow.audit.report import combine, findings
from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.compiler.scene.spec import Spec, scene_behaviours
from robofollow.compiler.splits.tasks import Splits


@dataclass(frozen=True)
class Compiled:
    """A compiled benchmark. Frozen all through (the audit is kept as text and read afresh):
    one compile is shared by every caller in a process (`compile_specs` caches it)."""

    spec: Spec
    splits: Splits
    training: Mapping[str, Behaviour]  # every training task's behaviour, by label (read-only)
    audit_json: str  # the audit, as audit.json holds it

    def __post_init__(self):
        object.__setattr__(self, "training", MappingProxyType(dict(self.training)))

    @classmethod
    def of(cls, spec: Spec, splits: Splits, training: Mapping[str, Behaviour],
           report: dict) -> Compiled:
        """A compiled benchmark from its parts, the audit as audit.json holds it."""
        return cls(spec, splits, training, json.dumps(report, indent=1, sort_keys=True) + "\n")

    def __reduce__(self):  # (a read-only mapping does not pickle; worker processes get copies)
        return Compiled, (self.spec, self.splits, dict(self.training), self.audit_json)

    @property
    def report(self) -> dict:
        """The audit (entropy, groups, counts, split rules, findings): a fresh copy."""
        return json.loads(self.audit_json)

    @cached_property
    def scene_digests(self) -> Mapping[str, str]:
        """Each scene's `Scene.digest`, computed once (every episode record hashes it)."""
        return MappingProxyType({scene.id: scene.digest for scene in self.spec.scenes.values()})

    @cached_property
    def split_digests(self) -> Mapping[str, str]:
        """Each scene's split digest: sha256 over the scene's digest and its test tasks in
        order, so it changes when, and only when, that scene's tests or what they start from
        change (never with the scenes compiled beside it)."""
        digests = {}
        for scene in self.spec.scenes.values():
            tasks = [t.model_dump_json() for t in self.splits.tasks if t.scene == scene.id]
            content = "\n".join([self.scene_digests[scene.id], *tasks])
            digests[scene.id] = hashlib.sha256(content.encode()).hexdigest()
        return MappingProxyType(digests)

    def candidates(self, scene: str) -> dict[str, Behaviour]:
        """The scene's training behaviours by label: what 'did instead' is matched against."""
        return scene_behaviours(self.spec, self.training, scene)


@dataclass(frozen=True)
class Part:
    """What some scenes compile to: their splits, and their part of the audit (`combine`),
    the best blind guesses included. A scene's depends on its own spec alone."""

    splits: Splits
    report: dict


def assemble(spec: Spec, training: Mapping[str, Behaviour],
             parts: list[Part]) -> Compiled:
    """The compiled benchmark of a spec from the parts of its scenes, in scene order."""
    splits = Splits(tasks=tuple(task for part in parts for task in part.splits.tasks),
                    rejected=tuple(r for part in parts for r in part.splits.rejected))
    return Compiled.of(spec, splits, training, combine(spec.digest, [p.report for p in parts]))


def clean(compiled: Compiled) -> bool:
    return findings(compiled.report) == 0
