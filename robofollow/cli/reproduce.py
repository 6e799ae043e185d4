"""`robofollow reproduce`: re-run recorded episodes of a run and say what agrees."""

from __future__ import annotations

from pathlib import Path

from robofollow.cli.common import positive, specs_of, specs_option


def add_reproduce(commands) -> None:
    p = commands.add_parser(
        "reproduce", help="re-run recorded episodes of a run and check they agree",
        description="Run N recorded episodes of a finished (or saved) run again, spread over "
                    "its scene x level cells, and compare them with the records: the scores "
                    "(Intent, Execution, completion) must agree on any machine; the "
                    "trajectory hashes must agree bit for bit where the run's recorded "
                    "environment (Python, NumPy, MuJoCo, JAX, CPU: RUN/run.json's provenance) "
                    "matches this one, and otherwise the versions that differ are named. "
                    "Nothing is written. Exit status 0: reproduced; 1: a score (or, in a "
                    "matching environment, a hash) differs.",
        epilog="examples:\n  robofollow reproduce docs/results/expert\n  robofollow "
               "reproduce docs/results/baselines/text --policy baseline:text --episodes 16")
    p.add_argument("run", metavar="RUN", help="a run folder (episodes.jsonl or scores.csv.gz)")
    p.add_argument("--episodes", type=positive, metavar="N",
                   help="how many recorded episodes to re-run (default: 8)")
    p.add_argument("--episode", action="append", metavar="ID",
                   help="re-run this recorded episode (e.g. scene2/L0/pickup_left_cube#r1); "
                        "may be repeated; instead of --episodes")
    p.add_argument("--policy", help="run them with this policy instead of the recorded one "
                                    "(e.g. baseline:NAME for a run made from the checkpoint "
                                    "folder it ships as)")
    p.add_argument("--workers", type=positive, default=1, metavar="N",
                   help="workers, one simulation each (default: 1)")
    specs_option(p)
    p.set_defaults(handler=cmd_reproduce)


def cmd_reproduce(args) -> int:
    from robofollow.compiled_cache import load
    from robofollow.errors import RoboFollowError, UsageError
    from robofollow.eval.policies.loading import check_policy
    from robofollow.eval.running.reproduce import DEFAULT_EPISODES, reproduce
    from robofollow.eval.running.saved_run import load_options

    if args.episode and args.episodes:
        raise UsageError("--episode names the episodes; --episodes picks that many: give one")
    run = Path(args.run)
    if args.policy:
        check_policy(args.policy)
    else:
        recorded = load_options(run).policy
        try:
            check_policy(recorded)
        except RoboFollowError as error:
            raise UsageError(f"{error.render()}: the run was made with that policy; --policy "
                             "re-runs its episodes with another (e.g. baseline:NAME)") from None
    found = reproduce(load(specs_of(args)), run, args.episodes or DEFAULT_EPISODES,
                      args.policy, args.workers, args.episode)
    print(found.text())
    return 0 if found.agrees else 1
