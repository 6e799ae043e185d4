"""Compile the benchmark: specs -> checked training tasks -> L0-L3 splits -> audit."""

from __future__ import annotations

import os
import time
from collections.abc import Mapping
from functools import lru_cache
from pathlib import Path

from robofollow.audit.splits import scene_audit
from robofollow.audit.task_list import listed_tests
from robofollow.benchmark.compiled import Compiled, Part, assemble
from robofollow.benchmark.guessing import blind_best, guessable
from robofollow.compiler.authoring.spec_files import spec_files
from robofollow.compiler.authoring.spec_loader import load_partial
from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.compiler.scene.spec import Spec
from robofollow.compiler.splits.generator import generate_examined
from robofollow.compiler.splits.tasks import TestTask
from robofollow.compiler.splits.training import training_behaviours
from robofollow.errors import SpecErrors


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
    seconds = {"load and check": time.perf_counter() - started, "generate splits": 0.0,
               "audit": 0.0}
    parts = [compile_scene(spec, scene, training, listed, seconds) for scene in spec.scenes]
    return assemble(spec, training, parts), seconds


def compile_scene(spec: Spec, scene: str, training: Mapping[str, Behaviour],
                  listed: tuple[TestTask, ...], seconds: dict[str, float]) -> Part:
    """Generate and audit one scene of a checked spec; the seconds each took are added to
    `seconds`."""
    alone = Spec(scenes={scene: spec.scenes[scene]}, digest=spec.digest)
    mark = time.perf_counter()
    splits, examined = generate_examined(alone, training,
                                         tuple(t for t in listed if t.scene == scene))
    seconds["generate splits"] += time.perf_counter() - mark
    mark = time.perf_counter()
    report = scene_audit(alone, training, splits, examined)
    report["blind_best"] = blind_best(alone, training, splits.tasks)
    report["guessable"] = guessable(alone, report["blind_best"])
    seconds["audit"] += time.perf_counter() - mark
    return Part(splits, report)
