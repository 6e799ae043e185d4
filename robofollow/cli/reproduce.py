"""`robofollow reproduce`: re-run recorded episodes of a run and say what agrees."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from robofollow.cli.common import benchmark_options, positive, run_benchmark_of


def add_reproduce(commands) -> None:
    p = commands.add_parser(
        "reproduce", help="re-run recorded episodes of a run and check they agree",
        description="Run N recorded episodes of a finished (or saved) run again, spread over "
                    "its scene x level cells, and compare them with the records: the scores "
                    "(Intent, Execution, completion) must agree (on another CPU a rollout can drift, "
                    "and an episode near a threshold score otherwise with it); the "
                    "trajectory hashes must agree bit for bit where the run's recorded "
                    "environment (Python, NumPy, MuJoCo, JAX, CPU: RUN/run.json's provenance) "
                    "matches this one, and otherwise the versions that differ are named. "
                    "The episodes come from the run's own release (RUN/run.json names it; a "
                    "run made before runs named theirs reads the release of its specs), so "
                    "a run reproduces whatever the specs are now. Nothing is written. Exit status 0: reproduced; 1: a score (or, in a "
                    "matching environment, a hash) differs.",
        epilog="examples:\n  robofollow reproduce docs/results/expert\n  robofollow "
               "reproduce docs/results/baselines/text --episodes 16\n  robofollow "
               "reproduce runs/mine --policy runs/ckpt-mine",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("run", metavar="RUN", help="a run folder (episodes.jsonl or scores.csv.gz)")
    p.add_argument("--episodes", type=positive, metavar="N",
                   help="how many recorded episodes to re-run (default: 8)")
    p.add_argument("--episode", action="append", metavar="ID",
                   help="re-run this recorded episode (e.g. scene2/L0/pickup_left_cube#r1); "
                        "may be repeated; instead of --episodes")
    p.add_argument("--policy", help="run them with this policy instead of the recorded one "
                                    "(default: the recorded one; a checkpoint folder that is "
                                    "not here is stood in for by the run's shipped "
                                    "checkpoint, RUN/checkpoint or baseline:NAME)")
    p.add_argument("--workers", type=positive, default=1, metavar="N",
                   help="workers, one simulation each (default: 1)")
    benchmark_options(p, of_run=True)
    p.set_defaults(handler=cmd_reproduce)


def cmd_reproduce(args) -> int:
    from robofollow.errors import RoboFollowError, UsageError
    from robofollow.eval.policies.loading import check_policy
    from robofollow.eval.running.reproduce import DEFAULT_EPISODES, reproduce, stand_in
    from robofollow.eval.running.run_benchmark import described
    from robofollow.eval.running.saved_run import load_options

    if args.episode and args.episodes:
        raise UsageError("--episode names the episodes; --episodes picks that many: give one")
    run = Path(args.run)
    options = load_options(run)
    policy = args.policy
    if policy is None and (policy := stand_in(run, options.policy)) is not None:
        print(f"policy: {options.policy} is not here; the shipped {policy} stands in for it "
              "(--policy chooses another)", file=sys.stderr)
    try:
        check_policy(policy or options.policy)
    except RoboFollowError as error:
        if policy:
            raise
        raise UsageError(f"the run was made with --policy {options.policy!r}, which is not "
                         f"here ({error.render()}); --policy re-runs its episodes with "
                         "another (e.g. baseline:NAME)") from None
    benchmark = run_benchmark_of(run, args, options)
    print(f"benchmark: {described(options)}", file=sys.stderr)
    found = reproduce(benchmark, run, args.episodes or DEFAULT_EPISODES, policy, args.workers,
                      args.episode)
    print(found.text())
    return 0 if found.agrees else 1
