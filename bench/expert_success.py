"""The scripted expert on every compiled episode (every task, every round), rendering off.

    python bench/expert_success.py [--specs specs] [--workers 2] [--levels L0,L1,L2,L3]
                                   [--scenes scene1,...] [--rounds N] [--json out.json]

Each recording is scored by the oracle. Prints the share of episodes with full marks (Intent
1, Execution 1 and complete) per scene x level, and every other episode with the stages it lost.
Targets: >= 99% overall and no cell below 97%.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import defaultdict
from pathlib import Path

from robofollow.benchmark.pipeline import compile_specs
from robofollow.benchmark.rounds import all_episodes
from robofollow.compiler.scene.spec import LEVELS
from robofollow.eval.running.verify import run_expert_episodes

ROOT = Path(__file__).resolve().parent.parent


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--specs", default=str(ROOT / "specs"))
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--levels", default=",".join(LEVELS))
    parser.add_argument("--scenes", default="")
    parser.add_argument("--rounds", type=int, default=None, help="only the first N rounds")
    parser.add_argument("--json", help="write every result to this file")
    args = parser.parse_args(argv)
    compiled = compile_specs(Path(args.specs))
    levels, scenes = args.levels.split(","), [s for s in args.scenes.split(",") if s]
    todo = [e for e in all_episodes(compiled) if e.level in levels
            and (not scenes or e.scene in scenes)
            and (args.rounds is None or e.round <= args.rounds)]
    began = time.perf_counter()
    results = run_expert_episodes(Path(args.specs), todo, args.workers)
    wall = time.perf_counter() - began
    cells: dict[tuple[str, str], list[bool]] = defaultdict(list)
    for result in results:
        cells[result["scene"], result["level"]].append(result["full"])
    print(f"\nexpert scored in full (% of episodes), {len(results)} episodes, {args.workers} workers, "
          f"{wall / 60:.1f} min wall, {sum(r['seconds'] for r in results) / len(results):.2f} s "
          "per episode in a worker")
    print(f"{'':10}" + "".join(f"{level:>16}" for level in levels))
    for scene in sorted({s for s, _ in cells}):
        row = []
        for level in levels:
            done = cells.get((scene, level), [])
            row.append(f"{100 * sum(done) / len(done):6.1f} ({sum(done):4}/{len(done):4})"
                       if done else f"{'-':>16}")
        print(f"{scene:<10}" + "".join(f"{cell:>16}" for cell in row))
    total = sum(r["full"] for r in results)
    worst = min(100 * sum(v) / len(v) for v in cells.values())
    print(f"overall {100 * total / len(results):.2f}% ({total}/{len(results)}); "
          f"lowest cell {worst:.1f}%")
    means = {k: sum(r[k] for r in results) / len(results)
             for k in ("intent_score", "execution_score", "achieved")}
    print(f"mean Intent {means['intent_score']:.4f}, mean Execution "
          f"{means['execution_score']:.4f}, complete {100 * means['achieved']:.2f}%")
    failures = sorted((r for r in results if not r["full"]), key=lambda r: r["episode"])
    print(f"\nfailures: {len(failures) or 'none'}")
    for failure in failures:
        print(f"  {failure['episode']}: {'; '.join(failure['reasons'])}")
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1) + "\n")
    return 0 if 100 * total / len(results) >= 99 and worst >= 97 else 1


if __name__ == "__main__":
    sys.exit(main())
