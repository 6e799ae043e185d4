"""Parse throughput over the 229 training instructions with the cached parser.

    python bench/parse_bench.py [--runs 7] [--repeat 20]

Pins itself to one core, builds the parser once (not timed), then times `repeat` passes over
the training set per run and reports the median, min and max instructions per second.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from pathlib import Path

from robofollow.compiler import parser

DATA = Path(__file__).resolve().parent.parent / "tests" / "data" / "training_instructions.json"


def main() -> None:
    args = argparse.ArgumentParser(description=__doc__,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    args.add_argument("--runs", type=int, default=7, help="timed runs (median reported)")
    args.add_argument("--repeat", type=int, default=20, help="passes over the set per run")
    options = args.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    texts = [text for task in json.loads(DATA.read_text()) for text in task["paraphrases"]]
    started = time.perf_counter()
    parser.parse(texts[0])
    build = time.perf_counter() - started
    rates = []
    for _ in range(options.runs):
        started = time.perf_counter()
        for _ in range(options.repeat):
            for text in texts:
                parser.parse(text)
        rates.append(options.repeat * len(texts) / (time.perf_counter() - started))
    print(f"instructions: {len(texts)} x {options.repeat} per run, {options.runs} runs, 1 core")
    print(f"parser build (once): {build * 1000:.0f} ms")
    print(f"parse rate: median {statistics.median(rates):,.0f}/s "
          f"(min {min(rates):,.0f}, max {max(rates):,.0f}); "
          f"{1e6 / statistics.median(rates):.0f} us per instruction")


if __name__ == "__main__":
    main()
