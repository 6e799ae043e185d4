"""`robofollow eval` and `robofollow report`: a policy evaluated over the splits, and its
report."""

from __future__ import annotations

import argparse
import difflib
import json
import os
import sys
from dataclasses import replace
from pathlib import Path

from robofollow.cli.common import (
    benchmark_of,
    benchmark_options,
    interrupted,
    points,
    positive,
    run_benchmark_of,
    seconds,
)
from robofollow.compiler.scene.spec import LEVELS, MOTION_LEVELS, ROUNDS
from robofollow.errors import RoboFollowError, UsageError
from robofollow.eval.protocols.limits import CALL_TIMEOUT_S, MAX_MESSAGE_BYTES
from robofollow.eval.running.deadline import DEFAULT_POLICY_TIMEOUT
from robofollow.eval.running.modes import (
    EXPORTS,
    INSTRUCTION_MODES,
    POWER_GROUPS,
    VIDEO_MODES,
)
from robofollow.sim import CHUNK
from robofollow.workers import EXECUTORS


def add_eval(commands) -> None:
    p = commands.add_parser(
        "eval", help="evaluate a policy over L0-L3: the paper's Table 1",
        description="Run a policy on the compiled episodes (fixed action budget, chunks of at "
                    f"most {CHUNK} actions, the tasks' seeds), score every episode with "
                    "the oracle, append the results to RUN/episodes.jsonl and write "
                    "RUN/summary.json; prints IS / ES / CR per scene and level. Interrupted "
                    "runs continue with --resume.",
        epilog="examples:\n  robofollow eval --policy expert --out runs/expert\n  robofollow "
               "eval --policy expert --out runs/quick --sample 2 --rounds 1\n  robofollow "
               "eval --policy blind --out runs/blind --levels L0,L1 --rounds 2\n  robofollow "
               "eval --policy mypkg.policies:make --out runs/mine\n\n"
               "A policy failure (an exception or SystemExit in the policy, invalid actions, a "
               "call past\n--policy-timeout, a module:factory policy's process dying, a "
               "server lost) ends its episode,\nwhich is scored as it stands and recorded "
               "with the reason; the run goes on. A policy that\ncannot be built stops the "
               "run before any episode.\n\nexit status: 0 the run finished; 3 it finished "
               "and some episodes ended in a policy failure\n(counted in the summary); 1 an "
               "error stopped it (finished episodes are kept: --resume);\n130 interrupted.",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--policy", required=True,
                   help="expert, blind, noop, random, baseline:NAME (a shipped baseline), a "
                        "checkpoint folder, module:factory, ws://HOST:PORT (openpi) or "
                        "tcp://HOST:PORT (upstream); servers take ?timeout=S&retries=N")
    p.add_argument("--out", required=True, metavar="RUN", help="run folder")
    benchmark_options(p)
    p.add_argument("--scenes", metavar="LIST", help="comma-separated scenes (default: all)")
    p.add_argument("--levels", metavar="LIST", help="comma-separated levels (default: all)")
    p.add_argument("--tasks", metavar="LIST", help="comma-separated task ids, e.g. "
                   "scene2/L0/pickup_left_cube (default: every task of the scenes and levels)")
    p.add_argument("--sample", type=positive, metavar="N",
                   help="only N tasks of each scene and level, evenly spread over its task "
                        "list (a quick look; default: every task)")
    p.add_argument("--shard", metavar="I/N",
                   help="run only the I-th of N parts of the episodes (round-robin over the "
                        "episode list), e.g. one task of a job array; robofollow merge joins "
                        "the N shard folders into one run")
    p.add_argument("--rounds", type=positive, default=ROUNDS, metavar="N",
                   help=f"rounds per task, each with its own seed (default: {ROUNDS})")
    p.add_argument("--workers", type=positive, default=os.cpu_count() or 1, metavar="N",
                   help="workers, one simulation each (default: the number of CPUs)")
    p.add_argument("--executor", choices=EXECUTORS, default="process",
                   help="process: a local process pool; ray: Ray actors on the cluster at "
                        "RAY_ADDRESS, or a local one (needs robofollow[ray]); the results are "
                        "the same (default: process)")
    p.add_argument("--instruction-mode", choices=INSTRUCTION_MODES,
                   default="normal", help="the episode's instruction, none, or another "
                                          "task's (default: normal)")
    p.add_argument("--controls", metavar="LIST",
                   help="control arms run after the run on the very same episodes, each in "
                        "RUN/controls/<mode> with its own summary: empty (no instruction) "
                        "and/or shuffled (another task's); the report adds the language "
                        "effect (instructed - control) with paired intervals over tasks")
    p.add_argument("--until-separated", metavar="RUN_B",
                   help="add rounds one at a time (up to --rounds) and stop once the run's "
                        "average Intent is told apart from RUN_B's on the same episodes "
                        "(paired sign-flip test over tasks at 0.05 / --rounds after each "
                        "round; RUN/sequential.json says where it stopped)")
    p.add_argument("--video", choices=VIDEO_MODES, default="none",
                   help="write mp4s of these episodes to RUN/videos, each frame captioned "
                        "with the instruction and the step; the report shows a sample beside "
                        "each cell (default: none). Rendering makes every episode about 10x "
                        "slower on a CPU, failures or not: an episode's outcome is known only "
                        "at its end, and 'failures' keeps only the failed ones")
    p.add_argument("--policy-timeout", type=seconds, metavar="S",
                   help="end an episode whose in-process policy takes longer than S seconds "
                        "over a reset() or act() call, recording it as a policy failure "
                        f"(default: {DEFAULT_POLICY_TIMEOUT:g}; servers take "
                        f"?timeout=S&retries=N, default {CALL_TIMEOUT_S:g})")
    p.add_argument("--allow-privileged", action="store_true",
                   help="let a policy server (ws:// or tcp://) that asks for them have "
                        "privileged observations: each episode's scene, layout and seed, from "
                        "which it can rebuild the simulation's ground truth. Without it such a "
                        "server is refused. Recorded in the run as ?privileged=1 on --policy; "
                        "servers also take ?max_message=BYTES (largest reply, default "
                        f"{MAX_MESSAGE_BYTES // 2 ** 20} MiB)")
    p.add_argument("--resume", action="store_true", help="continue an interrupted run")
    p.add_argument("--drop-corrupt", action="store_true",
                   help="with --resume: move corrupt lines of RUN/episodes.jsonl (which stop a "
                        "resume, with their line numbers) to RUN/episodes.jsonl.dropped and "
                        "evaluate their episodes again")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(handler=cmd_eval)


def _read_recorded(folders) -> None:
    """The run.json of each run to resume, checked as every reader of a run checks it (a bad
    one is one line naming the file and field) before its options are compared."""
    from robofollow.eval.running.run_folder import RUN_FILE, present
    from robofollow.eval.running.saved_run import read_run_file

    for out in folders:
        if present(out / RUN_FILE):
            read_run_file(out)


def cmd_eval(args) -> int:
    from robofollow.compiler.authoring.spec_loader import load_spec
    from robofollow.eval.policies.loading import check_policy, with_privileged
    from robofollow.eval.policies.policy_kind import is_server
    from robofollow.eval.reports.comparison import control_comparisons
    from robofollow.eval.reports.report import write_report
    from robofollow.eval.reports.tables import table_text
    from robofollow.eval.running.run_folder import CONTROLS, check_prepare, safe_path
    from robofollow.eval.running.runner import (
        EvalOptions,
        evaluate,
        failures_text,
        select_episodes,
        shard_of,
    )

    # what a typo can spoil is checked before the (slow) compile and before any file is
    # written (task ids need the compiled episodes: after the compile, before any file)
    check_policy(args.policy)
    if args.policy_timeout is not None and is_server(args.policy):
        raise UsageError("--policy-timeout limits in-process policies; a server takes "
                         "its own: --policy URL?timeout=S&retries=N")
    if args.drop_corrupt and not args.resume:
        raise UsageError("--drop-corrupt repairs a run being resumed: add --resume")
    if args.shard:
        shard_of(args.shard)
        if args.until_separated:
            raise UsageError("--until-separated decides when a whole run stops; a shard "
                             "is a part of one (run it without --shard)")
    controls = _names(args.controls, [m for m in INSTRUCTION_MODES if m != "normal"],
                      "control arm") if args.controls is not None else []
    if args.instruction_mode in controls:
        raise UsageError(f"--controls {args.instruction_mode}: the run itself gives "
                         f"{args.instruction_mode} instructions; a control arm compares "
                         "the instructed run with another mode")
    # a release reads in a blink; a working compile's specs load before they compile
    compiled = None if args.specs is not None else benchmark_of(args)
    spec = compiled.spec if compiled is not None else load_spec(Path(args.specs))
    scenes = _names(args.scenes, list(spec.scenes), "scene")
    levels = _names(args.levels, list(LEVELS), "level")
    policy = with_privileged(args.policy) if args.allow_privileged else args.policy
    source = ({"specs": str(Path(args.specs).resolve())} if compiled is None else
              {"release": compiled.release, "release_digest": compiled.release_digest})
    options = EvalOptions(policy, tuple(scenes), tuple(levels), args.rounds,
                          args.instruction_mode, args.video, spec.digest, (),
                          args.sample, args.policy_timeout if args.policy_timeout is not None
                          else None if is_server(args.policy) else DEFAULT_POLICY_TIMEOUT,
                          args.shard, tuple(controls), **source)
    arms = [(Path(args.out), options)] + [
        (safe_path(Path(args.out), CONTROLS, mode), options.arm(mode)) for mode in controls]
    if args.resume:
        _read_recorded(out for out, _ in arms)
    if args.tasks is None:
        for out, arm in arms:
            check_prepare(out, arm.to_json(), args.resume)
    compiled = compiled or benchmark_of(args)
    if args.tasks is not None:
        tasks = tuple(_names(args.tasks, list(compiled.task_ids), "task"))
        arms = [(out, replace(arm, tasks=tasks)) for out, arm in arms]
        options = arms[0][1]
        for out, arm in arms:
            check_prepare(out, arm.to_json(), args.resume)
    select_episodes(compiled, options)  # (a shard count past the episodes is refused)
    try:
        if args.until_separated:
            result, stopped = _until_separated(compiled, options, args)
            arms = [(out, replace(arm, rounds=stopped)) for out, arm in arms[1:]]
        for out, arm in arms:
            if arm.instruction_mode != options.instruction_mode:
                print(f"control arm: {arm.instruction_mode} instructions, {out}",
                      file=sys.stderr)
            outcome = evaluate(compiled, out, arm, args.workers, args.resume,
                               progress=not args.quiet, executor=args.executor,
                               drop_corrupt=args.drop_corrupt)
            if arm is options:
                result = outcome
            else:
                write_report(out)
    except KeyboardInterrupt:
        return interrupted("episodes", args.out)
    effects = control_comparisons(Path(args.out))
    try:
        markdown, _ = write_report(Path(args.out), controls=effects)
    except OSError as error:
        raise RoboFollowError(f"cannot write the report in {args.out}: "
                              f"{error.strerror or error} (the results are kept; "
                              f"robofollow report {args.out} writes it)") from None
    print(f"{args.policy} ({args.instruction_mode} instructions), {args.out}:")
    print(table_text(result))
    failures = failures_text(result)
    if failures:
        print(failures)
    for control in effects:
        print(f"language effect, instructed - {control['mode']} instructions (Intent):")
        print("\n".join(f"  {line}" for line in control["verdicts"]))
    print(f"report: {markdown} (and .html)")
    return 3 if failures else 0


def _until_separated(compiled, options, args) -> tuple[dict, int]:
    """Rounds one at a time until the declared test separates the run from the other
    (sequential.py); the summary and the last round run."""
    from robofollow.eval.reports.comparison import compare_runs, run_scores
    from robofollow.eval.running.run_folder import safe_path
    from robofollow.eval.running.runner import evaluate, select_episodes
    from robofollow.eval.statistics.sequential import SEQUENTIAL, look, record
    from robofollow.files import write_json_atomic

    other = Path(args.until_separated)
    run_scores(other)  # a run with episodes, said before anything runs
    out = Path(args.out)
    looks = min(options.rounds, max(e.round for e in select_episodes(compiled, options)))
    if looks < options.rounds:
        print(f"--rounds {options.rounds}: the benchmark holds {looks} rounds of these tasks, "
              f"so at most {looks} looks", file=sys.stderr)
    for round_index in range(1, looks + 1):
        result = evaluate(compiled, out, options, args.workers,
                          args.resume or round_index > 1, progress=not args.quiet,
                          executor=args.executor, drop_corrupt=args.drop_corrupt,
                          up_to_round=round_index)
        taken = look(compare_runs(out, other)["rows"], round_index, looks)
        print(f"after round {round_index}: average Intent {taken.difference:+.1f} against "
              f"{other.name}, p = {taken.p:.3g} (separated below {taken.threshold:.3g})",
              file=sys.stderr)
        if taken.separated:
            break
    write_json_atomic(safe_path(out, SEQUENTIAL), record(taken, other, looks))
    return result, taken.round


def _names(text: str | None, known: list[str], what: str) -> list[str]:
    """A comma-separated selection of known names, in any case (all of them when not
    given); a blank item, or a name not known, is an error (the latter offers the closest
    ones)."""
    by_lower = {name.lower(): name for name in known}
    if text is None:
        return list(known)
    chosen = [n.strip() for n in text.split(",")]
    if not all(chosen):
        raise UsageError(f"{text!r}: a blank {what} in the list; name each {what}, "
                         "separated by commas")
    unknown = [n for n in chosen if n.lower() not in by_lower]
    if unknown:
        hints = [by_lower[m] for n in unknown
                 for m in difflib.get_close_matches(n.lower(), list(by_lower), n=1)]
        listed = (f"did you mean {', '.join(dict.fromkeys(hints))}?" if hints
                  else f"known: {', '.join(known[:12])}{' …' if len(known) > 12 else ''}")
        raise UsageError(f"unknown {what} {', '.join(unknown)}; {listed}")
    picked = {by_lower[n.lower()] for n in chosen}
    return [n for n in known if n in picked]


def add_report(commands) -> None:
    p = commands.add_parser(
        "report", help="rebuild a run's report, or compare runs",
        description="With one RUN: rebuild its report (RUN/report.md, report.html, tasks.html "
                    "and the figures in RUN/figures/, SVG and PDF) from its episode records "
                    "or, for a run that keeps only its scores.csv.gz (as the runs in "
                    "docs/results do), from that file; a report is never rebuilt from fewer episodes than the "
                    "run's summary counts. With several: their Table 1 cells side by side on "
                    "the episodes every run holds (said when they hold different ones), each "
                    "later run's differences from the first and its paired differences with "
                    "intervals over tasks. L1 and L3 are also given for their moved and "
                    "as-trained tasks; records written before they carried their task's "
                    "motion take it from the compiled episodes when the specs are the run's "
                    "(else it is unknown: \"-\").",
        epilog="examples:\n  robofollow report runs/blind\n  robofollow report runs/blind "
               "--export latex\n  robofollow report runs/expert runs/blind runs/noop --out "
               "runs/three",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("runs", nargs="+", metavar="RUN", help="one run folder, or several to compare")
    p.add_argument("--out", metavar="PATH",
                   help="comparisons: a folder for comparison.md, comparison.html and the "
                        "figure of every run on one axis (a FILE.md: the markdown only); "
                        "default: print the markdown")
    p.add_argument("--export", choices=sorted(EXPORTS), action="append",
                   help="one run: also write Table 1 with its intervals for a paper "
                        "(RUN/table1.csv, RUN/table1.tex); may be repeated")
    benchmark_options(p, of_run=True)
    p.set_defaults(handler=cmd_report)


def cmd_report(args) -> int:
    from robofollow.eval.reports.comparison import environment_warnings
    from robofollow.eval.reports.report import (
        compare_reports,
        comparison_markdown,
        write_comparison,
        write_report,
    )
    from robofollow.eval.running.run_folder import check_folder_out, write_text_file

    runs = [Path(run) for run in args.runs]
    if len(runs) == 1 and args.out:
        raise UsageError(f"--out is for a comparison of several runs; one run's report is "
                         f"written in the run itself ({runs[0]}/report.md)")
    if len(runs) > 1 and args.export:
        raise UsageError("--export writes one run's Table 1: give one RUN")
    if args.out and not args.out.endswith(".md"):
        check_folder_out(Path(args.out))
    motions = [_motions(run, args) for run in runs]
    if len(runs) == 1:
        markdown, html = write_report(runs[0], motions[0])
        print(f"wrote {markdown}, {html} and {runs[0] / 'tasks.html'}")
        for kind in args.export or ():
            print(f"wrote {_export(runs[0], kind)}")
        return 0
    found = compare_reports(runs, motions)
    for line in [*found.warnings, *environment_warnings(runs)]:
        print(f"warning: {line}", file=sys.stderr)
    if args.out and not args.out.endswith(".md"):
        paths = write_comparison(found, Path(args.out))
        print(f"wrote {', '.join(str(p) for p in paths)}")
    elif args.out:
        write_text_file(Path(args.out), comparison_markdown(found))
        print(f"wrote {args.out}")
    else:
        print(comparison_markdown(found))
    return 0


def _export(run: Path, kind: str) -> Path:
    from robofollow.eval.reports.export import table1_csv, table1_latex
    from robofollow.eval.running.run_folder import safe_path, write_text_file
    from robofollow.eval.running.runner import summary
    from robofollow.eval.running.saved_run import load_run

    options, results = load_run(run)
    found = summary(results, options)
    path = safe_path(run, EXPORTS[kind])
    write_text_file(path, table1_csv(found) if kind == "csv" else table1_latex(
        found, f"RoboFollow Table 1: {options.policy}, {found['episodes']} episodes; "
               "Intent, Execution and Completion (0-100) with 95% intervals over tasks."))
    return path


def add_merge(commands) -> None:
    p = commands.add_parser(
        "merge", help="join the shards of a run (eval --shard I/N) into one run",
        description="Join the N shard folders of one run (eval --shard 1/N ... N/N, the same "
                    "options otherwise) into a new run folder: its episodes.jsonl in the run's "
                    "episode order, summary, scores and report. Refused, naming them, when a "
                    "shard or an episode is missing or doubled, or the options or specs differ.",
        epilog="example: robofollow eval --policy blind --shard 1/2 --out runs/b1 & robofollow "
               "eval --policy blind --shard 2/2 --out runs/b2; robofollow merge runs/b1 "
               "runs/b2 --out runs/blind")
    p.add_argument("shards", nargs="+", metavar="SHARD", help="the shard run folders")
    p.add_argument("--out", required=True, metavar="RUN", help="the merged run folder (new)")
    benchmark_options(p, of_run=True)
    p.set_defaults(handler=cmd_merge)


def cmd_merge(args) -> int:
    from robofollow.eval.reports.report import write_report
    from robofollow.eval.reports.tables import table_text
    from robofollow.eval.running.merge import merge

    shards = [Path(s) for s in args.shards]
    result, folders = merge(run_benchmark_of(shards[0], args), shards, Path(args.out))
    for folder in folders:
        write_report(folder)
    print(f"merged {len(args.shards)} shards into {args.out} ({result['episodes']} episodes):")
    print(table_text(result))
    return 0


def add_compare(commands) -> None:
    p = commands.add_parser(
        "compare", help="is run A really better than run B? paired differences with intervals",
        description="Pair the episodes of RUN_A and each later run by id (checking their "
                    "episode hashes and, where recorded, their realised starts) and give, for every scene x level cell, every level and "
                    "the average, the difference in IS, ES and CR (A - B, points) with a 95% "
                    "interval over tasks (a cluster bootstrap) and a sign-flip p-value over "
                    "tasks, adjusted by Holm's method; one verdict per level. Reads each run's "
                    "episodes.jsonl, or its scores.csv.gz where it keeps only that (the "
                    "shipped results in docs/results). See docs/statistics.md.",
        epilog="example: robofollow compare docs/results/baselines/scene2-text "
               "docs/results/baselines/scene2-blind")
    p.add_argument("runs", nargs="+", metavar="RUN", help="RUN_A RUN_B [RUN_C ...]: each "
                   "later run is compared with the first")
    p.add_argument("--power", type=points, metavar="DELTA",
                   help="plan instead of compare: the rounds per task needed to tell apart a "
                        "difference of DELTA points at each level (80%% power), from one pilot "
                        "run's variance or, better, from two pilot runs' paired differences")
    p.add_argument("--metric", choices=("IS", "ES", "CR"),
                   help="with --power: the metric planned for (default: IS)")
    p.add_argument("--by", choices=POWER_GROUPS,
                   help="with --power: plan for each level (default) or each scene x level "
                        "cell, alpha split over them; each row says the power the pilot's own "
                        "tasks and rounds reach")
    p.add_argument("--json", action="store_true", help="print the comparison as JSON")
    p.add_argument("--out", metavar="DIR", help="write compare.md, compare.html (with a forest "
                   "plot per metric) and compare.json here (one pair) or DIR/<A>-vs-<B>/ "
                   "(several)")
    p.set_defaults(handler=cmd_compare)


def cmd_compare(args) -> int:
    from robofollow.eval.reports.comparison import compare_runs, environment_warnings
    from robofollow.eval.reports.comparison_page import (
        comparison_folders,
        markdown,
        write_comparison_files,
    )

    runs = [Path(run) for run in args.runs]
    if args.power is not None:
        return _plan(runs, args)
    if args.metric is not None or args.by is not None:
        raise UsageError("--metric and --by shape the plan --power makes; a comparison "
                         "gives every metric in every cell")
    if len(runs) < 2:
        raise UsageError("compare takes at least two runs: RUN_A RUN_B [RUN_C ...] (or "
                         "one or two pilot runs with --power DELTA)")
    folders = comparison_folders(runs[0], runs[1:], Path(args.out)) if args.out else []
    results = [compare_runs(runs[0], other) for other in runs[1:]]
    for warning in [w for result in results for w in result["warnings"]] + \
            environment_warnings(runs):
        print(f"warning: {warning}", file=sys.stderr)
    for result, out in zip(results, folders, strict=False):
        write_comparison_files(result, out)
        print(f"wrote {out / 'compare.md'}, compare.html and compare.json", file=sys.stderr)
    if args.json:
        print(json.dumps(results[0] if len(results) == 1 else results, indent=2))
    elif not args.out:
        print("\n".join(markdown(result) for result in results))
    return 0


def _plan(runs: list[Path], args) -> int:
    from robofollow.eval.reports.comparison import run_scores
    from robofollow.eval.statistics.power import plan, plan_markdown

    if len(runs) > 2:
        raise UsageError("--power plans from one pilot run, or two (their paired "
                         "differences)")
    if args.out:
        raise UsageError("--out writes a comparison's files; --power prints a plan "
                         "(--json prints it as JSON)")
    metric = args.metric or "IS"
    entries = plan([run_scores(run) for run in runs], args.power, metric,
                   by=args.by or "level")
    print(json.dumps(entries, indent=2) if args.json else
          plan_markdown([run.name for run in runs], args.power, metric, entries))
    return 0


def _motions(run: Path, args) -> dict[str, str | None]:
    """The motion of each L1 / L3 episode of a run whose records do not carry it (written
    before they did), from the episodes of the run's benchmark where it is here; else none
    (their motion is unknown)."""
    from robofollow.eval.running.saved_run import load_run

    options, results = load_run(run)
    missing = [r["episode"] for r in results if "motion" not in r and r["level"] in MOTION_LEVELS]
    if not missing:
        return {}
    try:
        episodes = run_benchmark_of(run, args, options)
    except RoboFollowError as error:
        print(f"{run}: {len(missing)} L1/L3 records do not say whether their task's motion "
              f"moved, and its benchmark is not here ({error.render().splitlines()[0]}): "
              "shown as unknown", file=sys.stderr)
        return {}
    return {episode: episodes.record(episode).motion for episode in missing
            if episode in episodes.index}
