"""`robofollow compile` and `robofollow audit`: the specs compiled into splits, and audited."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

from robofollow.cli.common import specs_argument, specs_of
from robofollow.errors import RoboFollowError


def add_compile(commands) -> None:
    p = commands.add_parser(
        "compile", help="compile the specs into validated L0-L3 splits",
        description="Load the .rf specs, check every training task, generate the L0-L3 "
                    "splits from the split rules, audit them, and write the episodes, goal "
                    "DAGs, rejected candidates, audit.json and summary.txt. Exit status 1 on "
                    "a bad spec or any audit finding.")
    specs_argument(p)
    p.add_argument("--out", required=True, metavar="DIR", help="output folder")
    p.add_argument("--verify", type=int, nargs="?", const=1, default=0, metavar="ROUNDS",
                   help="then run the scripted expert on the first ROUNDS rounds (default 1) "
                        "of every test task in simulation and list the episodes it does not "
                        "score in full, with the stages lost (exit status 1 if any)")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="simulation workers for --verify (default: the number of CPUs)")
    p.set_defaults(handler=cmd_compile)


def cmd_compile(args) -> int:
    from robofollow.benchmark.output import check_out, write
    from robofollow.benchmark.pipeline import clean, compile_specs
    from robofollow.benchmark.summary import summary

    check_out(Path(args.out))  # before the work: an --out that cannot take the build is refused
    specs = specs_of(args)
    compiled = compile_specs(specs)
    changed = write(compiled, Path(args.out))
    print(summary(compiled, changed), end="")
    print(f"written to {args.out}")
    verified = _verify(compiled, specs, args.verify, args.workers) if args.verify else True
    return 0 if clean(compiled) and verified else 1


def _verify(compiled, specs: Path, rounds: int, workers: int | None) -> bool:
    """The expert on the first `rounds` rounds of every test task; failures listed."""
    from robofollow.benchmark.rounds import all_episodes
    from robofollow.eval.verify import run_expert_episodes

    episodes = [e for e in all_episodes(compiled) if e.round <= rounds]
    print(f"\nverifying: the expert on {len(episodes)} episodes ({rounds} round"
          f"{'s' if rounds > 1 else ''} of every test task) in simulation")
    results = run_expert_episodes(specs, episodes, workers or os.cpu_count() or 1)
    failures = [r for r in results if not r["full"]]
    print(f"the expert scored in full on {len(results) - len(failures)} of {len(results)}; "
          f"failures: {len(failures) or 'none'}")
    for failure in failures:
        print(f"  {failure['episode']}: {'; '.join(failure['reasons'])}")
    return not failures


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
    from robofollow.benchmark.pipeline import clean, compile_specs
    from robofollow.benchmark.summary import summary
    from robofollow.files import write_jsonl

    compiled = compile_specs(specs_of(args))
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
        if listed is not None:
            print(_task_list_text(args.tasks, listed), end="")
    return 0 if clean(compiled) and not (listed and listed["findings"]) else 1


def _task_list_text(path: str, listed: dict) -> str:
    """Findings grouped by kind, with counts."""
    from robofollow.audit.task_list import FINDING_KINDS

    findings = listed["findings"]
    lines = ["", f"task list {path}: {listed['checked']} tasks checked, "
                 f"{len(findings) or 'no'} finding{'' if len(findings) == 1 else 's'}"]
    for kind in FINDING_KINDS:
        items = [f for f in findings if f["kind"] == kind]
        if items:
            lines.append(f"{kind}: {len(items)}")
            lines += [f"  {f['id']}: {f['message']}" for f in items]
    return "\n".join(lines) + "\n"
