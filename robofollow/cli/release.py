"""`robofollow release`: the frozen benchmark releases: list them, show one, diff two, and the
state of a folder of results against the current one."""

from __future__ import annotations

import argparse
from pathlib import Path

from robofollow.errors import RoboFollowError, UsageError


def add_release(commands) -> None:
    p = commands.add_parser(
        "release", help="the frozen test sets: list, show, diff, and the state of results",
        description="A release is the compiled test set frozen as data (scenes, layouts, "
                    "bodies, jitter, training behaviours, every episode) with a digest; every "
                    "run names the release it was made on. `robofollow compile SPECS --release "
                    "NAME` freezes a new one.",
        epilog="examples:\n  robofollow release list\n  robofollow release show v1\n  "
               "robofollow release diff v1 v2 --runs runs/expert-v1 runs/expert-v2\n  "
               "robofollow release state docs/results --out docs/results/state.md",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    tools = p.add_subparsers(dest="tool", metavar="TOOL", required=True)
    tools.add_parser("list", help="the shipped releases, the current one marked",
                     description="Each shipped release: its episodes, tasks, spec digest and "
                                 "digest; * marks the current one (what commands read by "
                                 "default).").set_defaults(handler=cmd_list)
    show = tools.add_parser("show", help="one release's manifest: counts per cell and what "
                                         "froze it",
                            description="A release's manifest: its digest, the spec and "
                                        "compiler digests, each scene's split digest and its "
                                        "tasks and episodes per level, the scoring profile's "
                                        "name, and the RoboFollow version and commit that froze "
                                        "it.")
    show.add_argument("name", metavar="NAME", help="a release, e.g. v1")
    show.set_defaults(handler=cmd_show)
    diff = tools.add_parser(
        "diff", help="what changed from release A to B, per cell; the parity of runs on both",
        description="Per scene x level cell, the tasks and episodes added, removed, changed and "
                    "unchanged from release A to B (an episode is unchanged where both hold its "
                    "id and what decides it: its world, seed, instruction and behaviour). With "
                    "--runs, a policy's run on A and its run on B side by side per cell, over "
                    "all their episodes and over the unchanged ones.")
    diff.add_argument("a", metavar="A", help="the earlier release")
    diff.add_argument("b", metavar="B", help="the later release")
    diff.add_argument("--runs", nargs=2, metavar=("RUN_A", "RUN_B"),
                      help="a run made on A and one made on B (the same policy): the parity "
                           "table")
    diff.set_defaults(handler=cmd_diff)
    state = tools.add_parser(
        "state", help="each run under a folder: its release, current or to redo",
        description="Every run under FOLDER (control arms included), from its run.json: its "
                    "policy, instructions, episodes, the release it was made on, and "
                    "'current' or 'on vN, to redo'. Prints a markdown table, or writes it to "
                    "--out.")
    state.add_argument("folder", metavar="FOLDER", help="a folder of runs, e.g. docs/results")
    state.add_argument("--out", metavar="FILE.md", help="write the table here")
    state.set_defaults(handler=cmd_state)


def cmd_list(args) -> int:
    from robofollow import release

    names = release.names()
    if not names:
        raise RoboFollowError("no release ships with this RoboFollow")
    print("  release  episodes  tasks  specs         digest")
    for name in names:
        found = release.manifest(name)
        tasks = sum(sum(scene.tasks.values()) for scene in found.scenes.values())
        mark = "*" if name == release.CURRENT else " "
        print(f"{mark} {name:<7} {found.episodes:>9,} {tasks:>6}  {found.spec_digest[:12]}  "
              f"{found.digest[:12]}")
    return 0


def cmd_show(args) -> int:
    from robofollow import release
    from robofollow.compiler.scene.spec import LEVELS

    found = release.manifest(args.name)
    current = " (current)" if args.name == release.CURRENT else ""
    print(f"release {found.release}{current}: {found.episodes:,} episodes; digest "
          f"{found.digest}")
    print(f"  specs {found.spec_digest[:16]}, compiler {found.code_digest[:16]}, scoring "
          f"profile {found.scoring.get('name')}; frozen by RoboFollow {found.robofollow}"
          + (f" at commit {found.commit[:12]}" if found.commit else ""))
    print(f"  {'scene':<8} split         " + "".join(f"{level:>11}" for level in LEVELS))
    for scene, entry in found.scenes.items():
        cells = "".join(f"{entry.tasks[level]:>4} ({entry.episodes[level]:>4})"
                        for level in LEVELS)
        print(f"  {scene:<8} {entry.split[:12]}  {cells}")
    print("  (tasks, and episodes in parentheses, per level)")
    return 0


def cmd_diff(args) -> int:
    from robofollow.eval.reports.release_diff import release_diff

    if args.a == args.b:
        raise UsageError(f"diff compares two releases: {args.a} twice")
    runs = (Path(args.runs[0]), Path(args.runs[1])) if args.runs else None
    print(release_diff(args.a, args.b, runs), end="")
    return 0


def cmd_state(args) -> int:
    from robofollow.eval.reports.release_state import state_markdown
    from robofollow.eval.running.run_folder import write_text_file

    folder = Path(args.folder)
    if not folder.is_dir():
        raise UsageError(f"{folder}: no such folder")
    text = state_markdown(folder)
    if args.out:
        write_text_file(Path(args.out), text)
        print(f"wrote {args.out}")
    else:
        print(text, end="")
    return 0
