"""`robofollow compile` and `robofollow audit`: the specs compiled into splits, and audited."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

from robofollow.cli.common import positive, specs_argument, specs_of
from robofollow.errors import RoboFollowError, UsageError, counted


def add_compile(commands) -> None:
    p = commands.add_parser(
        "compile", help="compile the specs into validated L0-L3 splits",
        description="Load the .rf specs, check every training task, generate the L0-L3 "
                    "splits from the split rules, audit them, and write the episodes, goal "
                    "DAGs, rejected candidates, audit.json and summary.txt. Exit status 1 on "
                    "a bad spec or any audit finding.")
    specs_argument(p)
    p.add_argument("--out", required=True, metavar="DIR", help="output folder")
    verify = p.add_mutually_exclusive_group()
    verify.add_argument("--verify", type=positive, nargs="?", const=1, default=None, metavar="ROUNDS",
                        help="run the scripted expert in simulation on the first ROUNDS rounds "
                             "(default 1) of every test task of the scenes whose split differs "
                             "from the folder's splits.lock (new or edited scenes, or the ones "
                             "a change to the compiler altered), and list the episodes it does "
                             "not score in full, with the stages lost (exit status 1 if any). "
                             "Without it, the same with one round")
    verify.add_argument("--verify-all", type=positive, nargs="?", const=1, default=None,
                        metavar="ROUNDS", help="the same on every scene")
    verify.add_argument("--no-verify", action="store_true",
                        help="skip the simulation check, also for scenes not in splits.lock")
    p.add_argument("--strict", action="store_true",
                   help="treat the warnings as errors: a cell whose best language-blind guess "
                        "exceeds chance by more than the scene's guess_margin fails the build "
                        "(exit status 1)")
    p.add_argument("--update-lock", action="store_true",
                   help="pin every scene's split digest and task counts in SPECS/splits.lock "
                        "(a clean build only; SPECS must be given)")
    p.add_argument("--release", metavar="NAME",
                   help="freeze the build as benchmark release NAME (e.g. v2) in the package's "
                        "releases, for eval --release NAME: a clean build whose every scene "
                        "is verified, now or when splits.lock pinned it; an existing release "
                        "is never overwritten")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="simulation workers for verifying (default: the number of CPUs)")
    p.set_defaults(handler=cmd_compile)


def cmd_compile(args) -> int:
    from robofollow.benchmark.compiled import clean
    from robofollow.benchmark.output import check_out, write
    from robofollow.benchmark.splits_lock import (
        check_lock,
        lock_path,
        read_lock,
        write_lock,
    )
    from robofollow.compiled_cache import build

    check_out(Path(args.out))  # before the work: an --out that cannot take the build is refused
    if args.release is not None:
        from robofollow.release import check_new

        if args.no_verify:
            raise UsageError("--release freezes a verified build: leave out --no-verify")
        check_new(args.release)
    if args.update_lock and args.no_verify:
        raise UsageError("--update-lock pins only splits the expert verified: leave out "
                         "--no-verify (the changed and new scenes are verified)")
    if args.update_lock and args.specs is None:
        raise UsageError("--update-lock rewrites SPECS/splits.lock: name the specs folder to "
                         "pin (without one it would be the built-in benchmark's, or ./specs)")
    specs = specs_of(args)
    lock = lock_path(specs)
    if args.update_lock and not (isinstance(specs, Path) and specs.is_dir()):
        raise RoboFollowError("--update-lock needs a specs folder (the lock sits beside the "
                              "specs)")
    locked = read_lock(lock)
    compiled, files = build(specs)
    print(write(compiled, Path(args.out), files), end="")
    warnings = _guess_warnings(compiled)
    print(f"written to {args.out}")
    check = check_lock(compiled, locked)
    if check.lines:
        where = lock if lock is not None and lock.is_file() else "no splits.lock"
        print(f"\nsplits against {where}:")
        print("\n".join(f"  {line}" for line in check.lines))
    elif locked:
        print(f"\nevery split is the one {lock} pins")
    if args.verify_all is not None:
        verified = _verify(compiled, specs, args.verify_all, args.workers,
                           tuple(compiled.spec.scenes))
    elif check.unlocked and not args.no_verify:
        verified = _verify(compiled, specs, args.verify or 1, args.workers, check.unlocked)
    else:
        verified = True
        if args.verify is not None:
            print(f"\nnothing to verify: every split is the one {lock} pins (verified when "
                  "it was pinned); --verify-all simulates every scene")
    ok = clean(compiled) and verified and not (args.strict and warnings)
    if args.strict and warnings:
        print(f"--strict: {counted(len(warnings), 'warning')} fail the build")
    if args.update_lock and ok:
        write_lock(lock, compiled)
        print(f"pinned the splits of {counted(len(compiled.spec.scenes), 'scene')} in {lock}")
    elif args.update_lock:
        print(f"{lock} left as it was: the build has findings or failed verification")
    if args.release is not None:
        _freeze(compiled, args.release, ok)
    return 0 if ok else 1


def _freeze(compiled, name: str, ok: bool) -> None:
    """Freeze a clean, verified build as release `name`; say so, or why not."""
    from robofollow.release import CURRENT, freeze
    from robofollow.resources import releases_dir

    if not ok:
        print(f"release {name} not frozen: the build has findings or failed verification")
        return
    frozen = freeze(compiled, name)
    print(f"froze release {name} in {releases_dir() / name}: {frozen.episodes:,} episodes, "
          f"digest {frozen.digest[:12]}; `robofollow eval --release {name}` reads it (the "
          f"default stays {CURRENT} until CURRENT in robofollow/release.py names it)")


def _guess_warnings(compiled) -> list:
    """The located warnings of the cells a language-blind guess passes too easily, printed
    to standard error."""
    from robofollow.benchmark.guess_warnings import guess_warnings

    warnings = guess_warnings(compiled.spec, compiled.report["guessable"])
    for warning in warnings:
        print(warning.render(), file=sys.stderr)
    return warnings


def _verify(compiled, specs: Path, rounds: int, workers: int | None,
            scenes: tuple[str, ...]) -> bool:
    """The expert on the first `rounds` rounds of every test task of `scenes`; failures
    listed."""
    from robofollow.benchmark.rounds import all_episodes
    from robofollow.eval.running.verify import run_expert_episodes

    episodes = [e for e in all_episodes(compiled) if e.round <= rounds and e.scene in scenes]
    workers = workers or os.cpu_count() or 1
    every = "" if scenes == tuple(compiled.spec.scenes) else "; --verify-all verifies every scene"
    print(f"\nverifying {', '.join(scenes)}: the expert on {counted(len(episodes), 'episode')} "
          f"({counted(rounds, 'round')} of every test task) in simulation, "
          f"{_about(len(episodes), workers)} on {counted(workers, 'worker')} (--no-verify skips "
          f"it{every})")
    results = run_expert_episodes(specs, episodes, workers)
    failures = [r for r in results if not r["full"]]
    print(f"the expert scored in full on {len(results) - len(failures)} of {len(results)}; "
          f"failures: {len(failures) or 'none'}")
    for failure in failures:
        print(f"  {failure['episode']}: {'; '.join(failure['reasons'])}")
    return not failures


EXPERT_EPISODE_SECONDS = 0.95  # a worker's wall seconds per expert episode without images
#   (bench/eval_bench.py, 2 workers on a quiet 2-core CPU: 125.9 episodes/min)


def _about(episodes: int, workers: int) -> str:
    """About how long `episodes` expert episodes take on `workers` workers, in words."""
    seconds = episodes * EXPERT_EPISODE_SECONDS / max(1, min(workers, episodes))
    return f"about {max(1, round(seconds))} s" if seconds < 90 else \
        f"about {round(seconds / 60)} min"


def add_audit(commands) -> None:
    p = commands.add_parser(
        "audit", help="audit the splits, or any task list: entropy, leakage, repertoire, "
                      "ambiguity",
        description="Compile the specs in memory and report the audit. With --tasks, also "
                    "audit a task list (JSON Lines: id, scene, level, layout, instruction, "
                    "optional expect) against the specs' scenes and training tasks: parse "
                    "errors, missing or ambiguous referents (also at the jitter extremes), "
                    "expectation mismatches, behaviours outside the training repertoire, "
                    "leakage and level inconsistencies. Exit status 1 on a bad spec or any "
                    "finding.")
    specs_argument(p)
    p.add_argument("--tasks", metavar="FILE.jsonl", help="a task list to audit")
    p.add_argument("--export-tasks", metavar="FILE.jsonl",
                   help="write the compiled test tasks as a task list (expect = the compiled "
                        "behaviour)")
    p.add_argument("--json", action="store_true",
                   help="print the audit as one JSON object (with --tasks: plus findings and "
                        "checked)")
    p.set_defaults(handler=cmd_audit)


def cmd_audit(args) -> int:
    from robofollow.audit.task_list import audit_task_list, read_task_list, task_list
    from robofollow.benchmark.compiled import clean
    from robofollow.benchmark.summary import summary
    from robofollow.compiled_cache import build
    from robofollow.files import write_jsonl

    compiled = build(specs_of(args))[0]
    if args.export_tasks:
        try:
            write_jsonl(Path(args.export_tasks), task_list(compiled.splits))
        except OSError as error:
            raise RoboFollowError(f"cannot write {args.export_tasks}: "
                                  f"{error.strerror or error}") from None
        print(f"wrote {len(compiled.splits.tasks)} test tasks to {args.export_tasks}",
              file=sys.stderr)
    report, listed = compiled.report, None
    if args.tasks:
        listed = audit_task_list(compiled.spec, compiled.training,
                                 read_task_list(Path(args.tasks)))
        report = {**report, **listed}
    if args.json:
        print(json.dumps(report, indent=1, sort_keys=True))
    else:
        print(summary(compiled), end="")
        _guess_warnings(compiled)
        if listed is not None:
            print(_task_list_text(args.tasks, listed), end="")
    return 0 if clean(compiled) and not (listed and listed["findings"]) else 1


def _task_list_text(path: str, listed: dict) -> str:
    """Findings grouped by kind, with counts."""
    from robofollow.audit.task_list import FINDING_KINDS

    findings = listed["findings"]
    lines = ["", (f"task list {path}: {counted(listed['checked'], 'task')} checked, "
                 f"{counted(len(findings), 'finding') if findings else 'no findings'}")]
    for kind in FINDING_KINDS:
        items = [f for f in findings if f["kind"] == kind]
        if items:
            lines.append(f"{kind}: {len(items)}")
            lines += [f"  {f['id']}: {f['message']}" for f in items]
    return "\n".join(lines) + "\n"
