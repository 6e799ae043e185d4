"""The scripted expert on every compiled episode (every task, every round), rendering off.

    python bench/expert_success.py [--specs specs] [--workers 2] [--levels L0,L1,L2,L3]
                                   [--scenes scene1,...] [--tasks ID,...] [--rounds N]
                                   [--json out.json]

The episodes are those of the specs' working compile (from the compile cache), run as
`robofollow compile --verify-all` runs them. Each recording is scored by the oracle. Prints the
share of episodes with full marks (Intent 1, Execution 1 and complete) per scene x level, and
every other episode with the stages it lost. Targets: >= 99% overall and no cell below 97%.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import defaultdict
from pathlib import Path

from robofollow.cli.common import positive
from robofollow.compiled_cache import load
from robofollow.compiler.scene.spec import LEVELS
from robofollow.errors import did_you_mean
from robofollow.eval.running.verify import run_expert_episodes

ROOT = Path(__file__).resolve().parent.parent


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--specs", default=str(ROOT / "specs"))
    parser.add_argument("--workers", type=positive, default=2)
    parser.add_argument("--levels", default=",".join(LEVELS))
    parser.add_argument("--scenes", default="", help="comma-separated scenes (default: all)")
    parser.add_argument("--tasks", default="", help="comma-separated task ids, e.g. "
                        "scene2/L0/pickup_left_cube (default: every task)")
    parser.add_argument("--rounds", type=positive, default=None, help="only the first N rounds")
    parser.add_argument("--json", help="write every result to this file")
    args = parser.parse_args(argv)
    compiled = load(Path(args.specs))  # what each worker reads (and fills the cache for them)
    levels, scenes, tasks = ([name for name in given.split(",") if name]
                             for given in (args.levels, args.scenes, args.tasks))
    for noun, names, known in (("level", levels, LEVELS),
                               ("scene", scenes, compiled.spec.scenes),
                               ("task", tasks, compiled.task_ids)):
        for name in (name for name in names if name not in known):
            hint = did_you_mean(name, known)
            parser.error(f"--{noun}s: no {noun} {name!r} in {args.specs}"
                         + (f"; {hint}" if hint else ""))

    def chosen(episode_id: str) -> bool:
        task, _, round_index = episode_id.partition("#r")
        scene, level, _ = task.split("/", 2)
        return (level in levels and (not scenes or scene in scenes)
                and (not tasks or task in tasks)
                and (args.rounds is None or int(round_index) <= args.rounds))

    todo = compiled.episodes(chosen)
    if not todo:
        parser.error("no episode is of the --levels, --scenes and --tasks given")
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
