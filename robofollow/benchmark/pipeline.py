"""Compile the benchmark: specs -> checked training tasks -> L0-L3 splits -> audit."""

from __future__ import annotations

import hashlib
import json
import os
import time
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property, lru_cache
from pathlib import Path
from types import MappingProxyType

from robofollow.audit.splits import audit, findings
from robofollow.audit.task_list import listed_tests
from robofollow.benchmark.guessing import blind_best, guessable
from robofollow.compiler.authoring.spec_files import spec_files
from robofollow.compiler.authoring.spec_loader import load_partial
from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.compiler.scene.spec import Spec, scene_behaviours
from robofollow.compiler.splits.generator import Splits, generate_examined
from robofollow.compiler.splits.training import training_behaviours
from robofollow.errors import SpecErrors


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


def compile_specs(specs: Path | list[Path]) -> Compiled:
    """Load, check, generate and audit; raises SpecErrors on bad specs."""
    if isinstance(specs, Path):
        return _compile_cached(Path(os.path.realpath(specs)), _mtimes(specs))
    return _compile(specs)


def _mtimes(folder: Path) -> tuple:
    """The state of every spec file the compile reads (the cache key)."""
    state = []
    for file in spec_files(folder):
        try:
            info = os.stat(file)
        except OSError:
            continue
        state.append((str(file), info.st_mtime_ns, info.st_size, info.st_ino))
    return tuple(state)


@lru_cache(maxsize=4)
def _compile_cached(specs: Path, _mtimes: tuple) -> Compiled:
    """One compile per specs folder and file state, per process."""
    return _compile(specs)


def _compile(specs: Path | list[Path]) -> Compiled:
    """Every error of the specs in one report: loading, training tasks, listed tests (the
    checks of tasks on layouts that failed to load are skipped rather than repeated)."""
    return compile_timed(specs)[0]


def compile_timed(specs: Path | list[Path]) -> tuple[Compiled, dict[str, float]]:
    """A compile (never cached), with the seconds each phase took: loading and checking the
    specs (parsing and grounding the training tasks), generating the splits, and the audit
    (the best blind guesses included). What bench/compile_bench.py times."""
    seconds: dict[str, float] = {}
    started = time.perf_counter()
    loaded = load_partial(specs)
    if loaded.spec is None:
        raise SpecErrors(loaded.errors)
    spec = loaded.spec
    training, training_errors = training_behaviours(spec, loaded.sources, loaded.suspect)
    listed, test_errors = listed_tests(spec, training, loaded.sources, loaded.suspect)
    errors = loaded.errors + training_errors + test_errors
    if errors:
        raise SpecErrors(errors)
    seconds["load and check"] = time.perf_counter() - started
    mark = time.perf_counter()
    splits, examined = generate_examined(spec, training, listed)
    seconds["generate splits"] = time.perf_counter() - mark
    mark = time.perf_counter()
    report = audit(spec, training, splits, examined)
    report["blind_best"] = blind_best(spec, training, splits.tasks)
    report["guessable"] = guessable(spec, report["blind_best"])
    seconds["audit"] = time.perf_counter() - mark
    return Compiled.of(spec, splits, training, report), seconds


def clean(compiled: Compiled) -> bool:
    return findings(compiled.report) == 0
