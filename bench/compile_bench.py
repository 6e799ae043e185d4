"""Time `robofollow compile`, cold and from the per-spec-file cache, beside the previous code.

    python bench/compile_bench.py [--runs 5] [--specs specs] [--baseline CHECKOUT]

- phases: where a cold compile goes, in this process: loading and checking the specs (parsing
  the instructions included), generating the splits (grounding, wording, jitter checks),
  auditing (the best blind guesses included), rendering the build's files and writing them;
- the command, each run in a process of its own as a user runs it (`robofollow compile SPECS
  --out DIR --no-verify`), on a copy of the specs:
  - cold: no compiled spec file in the cache;
  - unchanged: again, every spec file cached;
  - one spec edited: after appending a comment to one spec file (each in turn);
  - scene4 alone, edited / unchanged: `compile SPECS/scene4.rf` after editing it, then again.

  Each figure is the command's own seconds once its module is imported (`main`, with the
  imports it makes on the way), beside the targets; start-up (the interpreter and `import
  robofollow.cli`) is given once, apart. "cold, whole process" is the cold compile as a user
  runs it (`python -m robofollow.cli compile ...`): the CPU seconds (user + system) of the
  process from interpreter start to exit. With `--baseline CHECKOUT` (a checkout of the previous
  code, e.g. `git worktree add /tmp/previous HEAD~1`) each run of the command is paired with
  the same run of that code (current, previous, current, ...), and the median of the pairs'
  ratios is given.

Medians over the runs. Every run reads the instruction parser's tables from the cache folder,
as any process after the first does. The cache folders are temporary (ROBOFOLLOW_CACHE_DIR);
the user's cache is not touched.
"""

from __future__ import annotations

import argparse
import compileall
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from robofollow.benchmark.output import write
from robofollow.benchmark.pipeline import compile_timed
from robofollow.benchmark.render import rendered
from robofollow.compiler.language import parser

ROOT = Path(__file__).resolve().parent.parent
TARGETS = {"cold": 2.0, "unchanged": 0.3, "one spec edited": 1.0,
           "scene4 alone, edited": 1.0, "scene4 alone, unchanged": 0.3,
           "cold, whole process": 2.0}  # s, one quiet core
# one run of the command in a fresh process: its seconds once robofollow.cli is imported
COMMAND = """
import contextlib, io, json, sys, time
started = time.perf_counter()
from robofollow.cli import main
imported = time.perf_counter()
with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
    status = main(sys.argv[1:])
print(json.dumps({"status": status, "start-up": imported - started,
                  "command": time.perf_counter() - imported}))
"""


def phases(specs: Path) -> dict[str, float]:
    """One cold compile in this process, phase by phase (the pipeline's own timing, then
    rendering and writing the build)."""
    parser._machine.cache_clear()  # read the parser's tables again, as a fresh process does
    parser._lark.cache_clear()
    started = time.perf_counter()
    compiled, times = compile_timed(specs)
    mark = time.perf_counter()
    files = rendered(compiled)
    times["render outputs"] = time.perf_counter() - mark
    mark = time.perf_counter()
    with tempfile.TemporaryDirectory() as out:
        write(compiled, Path(out), files)
    times["write outputs"] = time.perf_counter() - mark
    times["total"] = time.perf_counter() - started
    return times


class Code:
    """A checkout whose `robofollow compile` is timed, with a cache and specs of its own."""

    def __init__(self, checkout: Path, folder: Path, specs: Path):
        self.checkout, self.folder = checkout, folder
        self.specs = Path(shutil.copytree(specs, folder / "specs"))
        self.env = {**os.environ, "PYTHONPATH": str(checkout),
                    "ROBOFOLLOW_CACHE_DIR": str(folder / "cache")}
        self.env.pop("ROBOFOLLOW_NO_CACHE", None)
        compileall.compile_dir(checkout / "robofollow", quiet=1)  # (as an installed package)
        self.run(self.specs)  # the parser's tables, built once into the cache folder

    def run(self, specs: Path) -> dict[str, float]:
        """One `robofollow compile` in a process of its own."""
        argv = ["compile", str(specs), "--out", str(self.folder / "out"), "--no-verify"]
        done = subprocess.run([sys.executable, "-c", COMMAND, *argv], env=self.env,
                              cwd=self.folder, capture_output=True, text=True, timeout=600)
        if done.returncode != 0 or not done.stdout.strip():
            sys.exit(f"compile_bench: the compile of {self.checkout} failed:\n{done.stderr}")
        return json.loads(done.stdout.splitlines()[-1])

    def process(self, specs: Path) -> float:
        """One cold `python -m robofollow.cli compile` as a user runs it: the CPU seconds
        (user + system) of its process, start and exit included."""
        shutil.rmtree(self.folder / "cache" / "compiled", ignore_errors=True)
        argv = ["compile", str(specs), "--out", str(self.folder / "out"), "--no-verify"]
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        done = subprocess.run([sys.executable, "-m", "robofollow.cli", *argv], env=self.env,
                              cwd=self.folder, capture_output=True, text=True, timeout=600)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        if done.returncode != 0:
            sys.exit(f"compile_bench: the compile of {self.checkout} failed:\n{done.stderr}")
        return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)

    def edit(self, name: str, index: int) -> None:
        with open(self.specs / name, "a", encoding="utf-8") as spec:
            spec.write(f"\n# edited {index}\n")

    def scenarios(self, index: int) -> dict[str, dict[str, float]]:
        """The command's runs of one round, by scenario."""
        shutil.rmtree(self.folder / "cache" / "compiled", ignore_errors=True)
        found = {"cold": self.run(self.specs), "unchanged": self.run(self.specs)}
        files = sorted(path.name for path in self.specs.glob("*.rf"))
        self.edit(files[index % len(files)], index)
        found["one spec edited"] = self.run(self.specs)
        scene4 = self.specs / "scene4.rf"
        if scene4.is_file():
            self.edit(scene4.name, index)
            found["scene4 alone, edited"] = self.run(scene4)
            found["scene4 alone, unchanged"] = self.run(scene4)
        found["cold, whole process"] = {"command": self.process(self.specs)}
        return found


def main() -> None:
    options = argparse.ArgumentParser(description=__doc__,
                                      formatter_class=argparse.RawDescriptionHelpFormatter)
    options.add_argument("--runs", type=int, default=5)
    options.add_argument("--specs", type=Path, default=ROOT / "specs")
    options.add_argument("--baseline", type=Path, metavar="CHECKOUT",
                         help="a checkout of the previous code, timed beside this one")
    args = options.parse_args()
    if args.baseline is not None and not (args.baseline / "robofollow").is_dir():
        options.error(f"--baseline {args.baseline}: no robofollow/ there (give the root of a "
                      "checkout of the previous code)")
    with tempfile.TemporaryDirectory() as root:
        os.environ["ROBOFOLLOW_CACHE_DIR"] = os.path.join(root, "phases")
        os.environ.pop("ROBOFOLLOW_NO_CACHE", None)
        parser._lark()  # the tables, built once into the cache folder
        runs = [phases(args.specs) for _ in range(args.runs)]
        codes = {"current": Code(ROOT, Path(root, "current"), args.specs)}
        if args.baseline is not None:
            codes["previous"] = Code(args.baseline.resolve(), Path(root, "previous"),
                                     args.specs)
        rounds = [{name: code.scenarios(index) for name, code in codes.items()}
                  for index in range(args.runs)]
    total = statistics.median(r["total"] for r in runs)
    print(f"compiling {args.specs}, {args.runs} runs each; a cold compile in this process: "
          f"{total:.2f} s")
    for phase in runs[0]:
        if phase != "total":
            value = statistics.median(r[phase] for r in runs)
            print(f"  {phase:<42} {value:6.2f} s  {100 * value / total:5.1f} %")
    header = f"\n{'robofollow compile':<26}{'current':>9}"
    print(header + (f"{'previous':>10}{'ratio':>8}" if "previous" in codes else "")
          + f"{'target':>9}")
    for scenario in rounds[0]["current"]:
        mine = [r["current"][scenario]["command"] for r in rounds]
        line = f"  {scenario:<24}{statistics.median(mine):7.2f} s"
        if "previous" in codes:
            theirs = [r["previous"][scenario]["command"] for r in rounds]
            ratio = statistics.median(a / b for a, b in zip(mine, theirs))
            line += f"{statistics.median(theirs):8.2f} s{ratio:8.2f}"
        print(f"{line}   <= {TARGETS[scenario]} s")
    start = statistics.median(r["current"][s]["start-up"] for r in rounds for s in r["current"]
                              if "start-up" in r["current"][s])
    print(f"  start-up (interpreter and `import robofollow.cli`, apart): {start:.2f} s")


if __name__ == "__main__":
    main()
