"""Wall time of compiling the specs, cold and from the per-spec-file cache.

    python bench/compile_bench.py [--runs 5] [--specs specs]

- cold: the full compile (specs -> splits -> audit -> files), with where it goes: loading and
  checking the specs (parsing the instructions included), generating the splits (grounding,
  wording, jitter checks), auditing, and writing the outputs;
- warm: `compiled_cache.load` (what an env, `expert`, `render` and `score` read) from a cache
  that holds every spec file;
- one spec edited: the same after appending a comment to one spec file (each in turn), which
  compiles that file's scenes again.

Medians over the runs, beside the targets. Every run reads the instruction parser's tables
from the cache folder, as any process after the first does. The cache folders are temporary
(ROBOFOLLOW_CACHE_DIR); the user's cache is not touched.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from robofollow import compiled_cache
from robofollow.benchmark.output import write
from robofollow.benchmark.pipeline import compile_timed
from robofollow.compiler.authoring.spec_files import spec_files
from robofollow.compiler.language import parser

ROOT = Path(__file__).resolve().parent.parent
TARGETS = {"cold": 2.0, "warm": 0.3, "one spec edited": 1.0}  # s, median on one quiet core


def cold(specs: Path) -> dict[str, float]:
    """One full compile, phase by phase (the pipeline's own timing, then writing)."""
    parser._machine.cache_clear()  # read the parser's tables again, as a fresh process does
    parser._lark.cache_clear()
    started = time.perf_counter()
    compiled, times = compile_timed(specs)
    mark = time.perf_counter()
    with tempfile.TemporaryDirectory() as out:
        write(compiled, Path(out))
    times["write outputs"] = time.perf_counter() - mark
    times["total"] = time.perf_counter() - started
    return times


def cached_load(specs: Path, before: Callable[[], None] = lambda: None) -> float:
    """One `compiled_cache.load` as a fresh process does it (the per-process memos
    cleared), after `before` (untimed)."""
    before()
    compiled_cache._assemble.cache_clear()
    compiled_cache.code_digest.cache_clear()
    started = time.perf_counter()
    compiled_cache.load(specs)
    return time.perf_counter() - started


def line(name: str, value: float) -> str:
    return f"{name:<16} median {value:6.2f} s  (target <= {TARGETS[name]} s)"


def main() -> None:
    options = argparse.ArgumentParser(description=__doc__,
                                      formatter_class=argparse.RawDescriptionHelpFormatter)
    options.add_argument("--runs", type=int, default=5)
    options.add_argument("--specs", type=Path, default=ROOT / "specs")
    args = options.parse_args()
    with tempfile.TemporaryDirectory() as root:
        os.environ["ROBOFOLLOW_CACHE_DIR"] = os.path.join(root, "cache")
        os.environ.pop("ROBOFOLLOW_NO_CACHE", None)
        parser._lark()  # the tables, built once into the cache folder
        runs = [cold(args.specs) for _ in range(args.runs)]
        specs = Path(shutil.copytree(args.specs, os.path.join(root, "specs")))
        files = spec_files(specs)
        compiled_cache.load(specs)  # fills the cache
        warm = [cached_load(specs) for _ in range(args.runs)]

        def edit(index: int) -> Callable[[], None]:
            def append() -> None:
                with open(files[index % len(files)], "a", encoding="utf-8") as spec:
                    spec.write(f"\n# edited {index}\n")
            return append

        edited = [cached_load(specs, edit(index)) for index in range(args.runs)]
    total = statistics.median(r["total"] for r in runs)
    print(f"compiling {args.specs}, {args.runs} runs each:")
    print(line("cold", total))
    for phase in runs[0]:
        if phase != "total":
            value = statistics.median(r[phase] for r in runs)
            print(f"  {phase:<42} {value:6.2f} s  {100 * value / total:5.1f} %")
    print(line("warm", statistics.median(warm)))
    print(line("one spec edited", statistics.median(edited)))


if __name__ == "__main__":
    main()
