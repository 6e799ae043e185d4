"""`robofollow generate` and `robofollow dataset check`: demonstration datasets."""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from robofollow.cli.common import (
    benchmark_of,
    image_size,
    interrupted,
    positive,
)
from robofollow.data.jobs import DEMO_INSTRUCTIONS, FORMATS
from robofollow.errors import RoboFollowError, UsageError


def add_generate(commands) -> None:
    p = commands.add_parser(
        "generate", help="record expert demonstrations of the training tasks as a dataset",
        description="Run the scripted expert on every training task (seeds fixed per task and "
                    "episode; an attempt the oracle does not score complete is discarded and "
                    "the next seed tried) and write a LeRobot v2.1 / v3.0 or HDF5 dataset with "
                    "the 14-D state and action, three camera videos and the instruction. "
                    "Interrupted runs continue with --resume.",
        epilog="examples:\n  robofollow generate --out demos/            # 50 per "
               "task, 3,750 episodes\n  robofollow generate --out small/ "
               "--tasks scene1,pickup_left_cube --episodes-per-task 3\n  robofollow dataset "
               "check demos/", formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("specs", nargs="?", help="a working compile of these specs (a .rf file or "
                                            "a folder) instead of a release, as a task author "
                                            "records demonstrations of new tasks")
    p.add_argument("--release", metavar="NAME", help="the benchmark release whose training "
                                                     "tasks to record (default: the current)")
    p.add_argument("--out", required=True, metavar="DIR", help="dataset folder (new or empty, "
                                                              "or the one to --resume)")
    p.add_argument("--episodes-per-task", type=positive, default=50, metavar="N",
                   help="demonstrations per training task (default: 50)")
    p.add_argument("--tasks", metavar="LIST", help="comma-separated training task labels "
                   "and/or scene ids (default: every training task)")
    p.add_argument("--workers", type=positive, default=os.cpu_count() or 1, metavar="N",
                   help="worker processes, one renderer each (default: the number of CPUs)")
    p.add_argument("--format", choices=FORMATS,
                   default="lerobot-v2.1", help="dataset format (default: lerobot-v2.1)")
    p.add_argument("--image-size", type=image_size, default=(320, 240), metavar="WxH",
                   help="camera image size (default: 320x240)")
    p.add_argument("--instructions", choices=DEMO_INSTRUCTIONS, default="sample",
                   help="sample: one paraphrase per episode; all: every paraphrase as its own "
                        "episode (default: sample)")
    p.add_argument("--resume", action="store_true",
                   help="continue an interrupted run in DIR (same options)")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p.set_defaults(handler=cmd_generate)


def cmd_generate(args) -> int:
    from robofollow.data.generate import generate
    from robofollow.data.jobs import select_tasks
    from robofollow.data.units import Options

    if args.specs is not None and args.release is not None:
        raise UsageError("SPECS (a working compile) or --release: give one")
    compiled = benchmark_of(args)
    width, height = args.image_size
    tasks = select_tasks(compiled, [t for t in (args.tasks or "").split(",") if t.strip()])
    options = Options(args.format, args.episodes_per_task, tuple(tasks), width, height,
                      args.instructions, compiled.spec.digest)
    try:
        result = generate(compiled, Path(args.out), options, args.workers, args.resume,
                          progress=not args.quiet)
    except KeyboardInterrupt:
        return interrupted("demonstrations", args.out)
    except OSError as error:
        raise RoboFollowError(f"cannot write the dataset in {args.out}: {error}") from None
    if result.already_complete:
        print(f"{args.out} is already complete: {result.episodes} episodes")
    else:
        print(f"{args.out}: {result.episodes} episodes ({args.format}) from "
              f"{result.demonstrations} demonstrations of {len(tasks)} tasks, "
              f"{result.recorded} recorded now, {result.discarded} attempts discarded, "
              f"{result.seconds / 60:.1f} min")
    for failure in result.failed:
        print(f"  failed: {failure['failed']}", file=sys.stderr)
    return 1 if result.failed else 0


def add_dataset(commands) -> None:
    p = commands.add_parser("dataset", help="dataset tools (check)",
                            description="Tools for generated datasets.")
    tools = p.add_subparsers(dest="tool", metavar="TOOL", required=True)
    q = tools.add_parser(
        "check", help="validate a dataset against its format's rules",
        description="Validate a LeRobot v2.1 / v3.0 or HDF5 dataset: features, shapes, dtypes, "
                    "fps, indices, timestamps, frame counts against the videos, statistics. "
                    "Prints the findings; exit status 1 when there is any.")
    q.add_argument("dataset", metavar="DIR", help="the dataset folder")
    q.add_argument("--json", action="store_true", help="print the report as JSON")
    q.set_defaults(handler=cmd_dataset_check)


def cmd_dataset_check(args) -> int:
    from robofollow.data.check import check

    report = check(Path(args.dataset))
    print(json.dumps(report.to_dict(), indent=1) if args.json else report.render())
    return 0 if report.ok else 1
