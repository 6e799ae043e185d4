"""Env start-up: `import robofollow.sim.env`, `RoboFollowEnv()` and the first `reset()`, each in
a fresh process, with a cold cache (an empty cache folder) and a warm one (after a first,
untimed start; target: construct + reset well under 1 s). The env reads the current release,
which needs no compile: the two show that the cache does not matter to it.

    python bench/env_start_bench.py [--cold 3] [--warm 5]

The cache folders are temporary (ROBOFOLLOW_CACHE_DIR); the user's cache is not touched.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

CHILD = """
import json, time
began = time.perf_counter()
import robofollow
from robofollow.sim.env import RoboFollowEnv
imported = time.perf_counter()
env = RoboFollowEnv()
constructed = time.perf_counter()
env.reset(seed=0)
done = time.perf_counter()
env.close()
print(json.dumps({"import": imported - began, "construct": constructed - imported,
                  "reset": done - constructed, "construct+reset": done - imported}))
"""


def start(cache: str) -> dict[str, float]:
    """The times of one env start in a fresh process with this cache folder."""
    env = {**os.environ, "ROBOFOLLOW_CACHE_DIR": cache}
    env.pop("ROBOFOLLOW_NO_CACHE", None)
    out = subprocess.run([sys.executable, "-c", CHILD], env=env, check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def report(name: str, runs: list[dict[str, float]]) -> None:
    medians = {key: statistics.median(run[key] for run in runs) for key in runs[0]}
    print(f"{name:<5} ({len(runs)} runs, medians): "
          + ", ".join(f"{key} {value:.3f} s" for key, value in medians.items()))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cold", type=int, default=3)
    parser.add_argument("--warm", type=int, default=5)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as root:
        cold = [start(os.path.join(root, f"cold{i}")) for i in range(args.cold)]
        warm_cache = os.path.join(root, "warm")
        start(warm_cache)  # a first start, untimed
        warm = [start(warm_cache) for _ in range(args.warm)]
    for name, runs in (("cold", cold), ("warm", warm)):
        if runs:
            report(name, runs)


if __name__ == "__main__":
    main()
