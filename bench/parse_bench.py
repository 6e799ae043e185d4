"""Parse throughput with the cached parser, over the 229 training instructions or the
paraphrase stress corpus (tests/data/stress: longer, politer, with the wider constructs).

    python bench/parse_bench.py [--corpus training|stress] [--runs 7] [--repeat 20]

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

from robofollow.cli.common import positive
from robofollow.compiler.language import parser

DATA = Path(__file__).resolve().parent.parent / "tests" / "data"


def corpus(name: str) -> list[str]:
    if name == "training":
        tasks = json.loads((DATA / "training_instructions.json").read_text())
        return [text for task in tasks for text in task["paraphrases"]]
    return [text for file in sorted((DATA / "stress").glob("*.json"))
            for entry in json.loads(file.read_text()) for text in entry["rewordings"]]


def main() -> None:
    args = argparse.ArgumentParser(description=__doc__,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    args.add_argument("--corpus", choices=("training", "stress"), default="training",
                      help="the instructions to parse")
    args.add_argument("--runs", type=positive, default=7, help="timed runs (median reported)")
    args.add_argument("--repeat", type=positive, default=20, help="passes over the set per run")
    options = args.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    texts = corpus(options.corpus)
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
    print(f"instructions: {len(texts)} ({options.corpus}) x {options.repeat} per run, "
          f"{options.runs} runs, 1 core")
    print(f"parser build (once): {build * 1000:.0f} ms")
    print(f"parse rate: median {statistics.median(rates):,.0f}/s "
          f"(min {min(rates):,.0f}, max {max(rates):,.0f}); "
          f"{1e6 / statistics.median(rates):.0f} us per instruction")


if __name__ == "__main__":
    main()
