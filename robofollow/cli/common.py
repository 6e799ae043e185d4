"""What the commands share: the specs they read, argument types, and small helpers."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from robofollow.errors import RoboFollowError
from robofollow.resources import builtin_specs

_SPECS_DEFAULT = "./specs when this folder has one, else the built-in benchmark"


def specs_argument(parser: argparse.ArgumentParser) -> None:
    """The optional SPECS operand of a command that reads nothing else."""
    parser.add_argument("specs", nargs="?", help="a spec file or a folder of .rf files "
                                                 "(default: " + _SPECS_DEFAULT + ")")


def benchmark_options(parser: argparse.ArgumentParser, of_run: bool = False) -> None:
    """--release and --specs: the benchmark a command reads (`of_run`: a command that reads a
    run, whose own release it reads by default)."""
    default = "the run's own" if of_run else "the current release"
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--release", metavar="NAME",
                       help=f"the frozen benchmark release to read, e.g. v1 (default: {default})")
    group.add_argument("--specs", metavar="PATH",
                       help="read a working compile of these specs (a .rf file or a folder) "
                            "instead of a release, as a task author does; recorded as such"
                            + (" (a run made so reads its own by default)" if of_run else ""))


def benchmark_of(args):
    """The benchmark a command reads: --specs's working compile, else --release's release,
    else the current release (compiled_cache.Episodes)."""
    from robofollow import release

    if args.specs is not None:
        return release.benchmark(specs=Path(args.specs))
    return release.benchmark(args.release)


def run_benchmark_of(run: Path, args, options=None):
    """The benchmark a command reads for `run`: its own release (or working compile), or
    --specs's (`options`: the run's, where already read)."""
    from robofollow.eval.running.run_benchmark import run_benchmark
    from robofollow.eval.running.saved_run import load_options

    return run_benchmark(run, options or load_options(run), args.release,
                         Path(args.specs) if args.specs is not None else None)


def specs_of(args) -> Path:
    """The specs a command reads: as given; else ./specs when the current folder has one;
    else the benchmark's own, installed with the package. Said on stderr when not given."""
    if args.specs is not None:
        return Path(args.specs)
    if Path("specs").is_dir():
        print("specs: ./specs (this folder's; --specs chooses others)", file=sys.stderr)
        return Path("specs")
    path = builtin_specs()
    print(f"specs: the built-in benchmark ({path})", file=sys.stderr)
    return path


def positive(text: str) -> int:
    """A whole number, at least 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


def seconds(text: str) -> float:
    """A finite positive number of seconds."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, got {text!r}") from None
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"must be a positive number of seconds, got {text}")
    return value


MIN_POINTS = 0.1  # the smallest difference a plan is made for: Table 1 shows one decimal


def points(text: str) -> float:
    """A difference in points (0-100 scores), from MIN_POINTS to 100."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of points, got {text!r}") from None
    if not MIN_POINTS <= value <= 100:  # (NaN fails too)
        raise argparse.ArgumentTypeError(f"must be between {MIN_POINTS:g} and 100 points, "
                                         f"got {text}")
    return value


def image_size(text: str) -> tuple[int, int]:
    """WIDTHxHEIGHT, each within 16..4096."""
    try:
        width, height = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT such as 320x240, got {text!r}") from None
    if not (16 <= width <= 4096 and 16 <= height <= 4096):
        raise argparse.ArgumentTypeError(f"image size {text} is out of range (16..4096)")
    return width, height


def scene_layout(compiled, scene: str, layout: str | None) -> str:
    """A scene's layout by name (default: its first), checked."""
    scenes = compiled.spec.scenes
    if scene not in scenes:
        raise RoboFollowError(f"no scene {scene!r}; scenes: {', '.join(scenes)}")
    layouts = scenes[scene].layouts
    layout = layout or next(iter(layouts))
    if layout not in layouts:
        raise RoboFollowError(f"scene {scene} has no layout {layout!r}; layouts: "
                              f"{', '.join(layouts)}")
    return layout


def interrupted(what: str, out: str) -> int:
    """Say what an interrupted run kept and how to go on; the exit status of Ctrl-C."""
    print(f"\ninterrupted: the finished {what} are kept in {out}; run the same command with "
          "--resume to continue", file=sys.stderr)
    return 130
