"""Wall time of the full compile (specs -> splits -> audit -> files) and where it goes.

    python bench/compile_bench.py [--runs 5] [--specs specs]

Reports the median over runs of each phase: loading and checking the specs (parsing the
instructions included), generating the splits (grounding, wording, jitter checks), auditing,
and writing the outputs; the target for the full compile is under 5 s.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

from robofollow.audit.splits import audit
from robofollow.benchmark.output import write
from robofollow.benchmark.pipeline import Compiled
from robofollow.compiler import parser
from robofollow.compiler.spec_loader import load_spec
from robofollow.compiler.splits import generate
from robofollow.compiler.training import check_training

ROOT = Path(__file__).resolve().parent.parent


def run_once(specs: Path) -> dict[str, float]:
    parser._lark.cache_clear()  # include building the instruction parser, as a fresh run does
    times = {}
    started = time.perf_counter()
    spec = load_spec(specs)
    training = check_training(spec)
    times["load and check (parse, ground training)"] = time.perf_counter() - started
    mark = time.perf_counter()
    splits = generate(spec, training)
    times["generate splits"] = time.perf_counter() - mark
    mark = time.perf_counter()
    report = audit(spec, training, splits)
    times["audit"] = time.perf_counter() - mark
    mark = time.perf_counter()
    with tempfile.TemporaryDirectory() as out:
        write(Compiled.of(spec, splits, training, report), Path(out))
    times["write outputs"] = time.perf_counter() - mark
    times["total"] = time.perf_counter() - started
    return times


def main() -> None:
    options = argparse.ArgumentParser(description=__doc__,
                                      formatter_class=argparse.RawDescriptionHelpFormatter)
    options.add_argument("--runs", type=int, default=5)
    options.add_argument("--specs", type=Path, default=ROOT / "specs")
    args = options.parse_args()
    runs = [run_once(args.specs) for _ in range(args.runs)]
    total = statistics.median(r["total"] for r in runs)
    print(f"full compile of {args.specs}: median {total:.2f} s over {args.runs} runs "
          f"(target < 5 s)")
    for phase in runs[0]:
        if phase != "total":
            value = statistics.median(r[phase] for r in runs)
            print(f"  {phase:<42} {value:6.2f} s  {100 * value / total:5.1f} %")


if __name__ == "__main__":
    main()
