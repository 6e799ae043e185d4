"""`robofollow merge`: the shards of one run (`eval --shard I/N`, e.g. the tasks of a job
array) joined into a run like any other. The shards must be the N parts of one run (the same
options but the shard, the same specs) and hold, together, every episode of the run exactly
once; otherwise nothing is written and the error names what is missing or doubled."""

from __future__ import annotations

from collections import Counter
from dataclasses import replace
from pathlib import Path

from robofollow.compiled_cache import Episodes
from robofollow.errors import RoboFollowError
from robofollow.eval.compare import named
from robofollow.eval.report import write_report
from robofollow.eval.run_folder import RESULTS, SCORES, SUMMARY, check_out, prepare, run_lock
from robofollow.eval.runner import EvalOptions, select_episodes, shard_of, summary, with_motion
from robofollow.eval.saved_run import load_run
from robofollow.eval.scores import write_scores
from robofollow.files import json_line, write_json_atomic


class MergeError(RoboFollowError):
    """Shards that do not make one run."""


def _whole(shards: list[Path], loaded: list[tuple[EvalOptions, list[dict]]]) -> EvalOptions:
    """The options of the run the shards are parts of, once they are checked to be its N
    parts."""
    whole = replace(loaded[0][0], shard=None)
    parts = []
    for shard, (options, _) in zip(shards, loaded, strict=True):
        if options.shard is None:
            raise MergeError(f"{shard} is a whole run, not a shard (eval --shard I/N makes one)")
        if replace(options, shard=None) != whole:
            theirs = replace(options, shard=None).to_json()
            differ = [k for k, v in whole.to_json().items() if theirs.get(k) != v]
            raise MergeError(f"{shard} was run with other options than {shards[0]} "
                             f"({', '.join(differ)} differ): shards of one run share them")
        parts.append(shard_of(options.shard))
    counts = {count for _, count in parts}
    if len(counts) != 1:
        raise MergeError(f"the shards split the run in different numbers of parts: "
                         f"{', '.join(o.shard for o, _ in loaded)}")
    count = counts.pop()
    seen = Counter(index for index, _ in parts)
    doubled = sorted(i for i, n in seen.items() if n > 1)
    missing = sorted(set(range(1, count + 1)) - set(seen))
    problems = [f"{what} {', '.join(f'{i}/{count}' for i in found)}"
                for found, what in ((missing, "missing"), (doubled, "doubled")) if found]
    if problems:
        raise MergeError("the shards are not the run's parts once each: " + "; ".join(problems))
    return whole


def merge(benchmark: Episodes, shards: list[Path], out: Path) -> dict:
    """Join the shards into the run folder `out` (new); returns its summary."""
    loaded = [load_run(shard) for shard in shards]
    options = _whole(shards, loaded)
    if options.spec_digest != benchmark.spec.digest:
        raise MergeError("the shards were run on other specs than these (--specs chooses the "
                         "run's)")
    episodes = select_episodes(benchmark, options)
    expected = [e.id for e in episodes]
    records = [record for _, results in loaded for record in results]
    seen = Counter(record["episode"] for record in records)
    missing = [e for e in expected if not seen[e]]
    doubled = sorted(e for e, n in seen.items() if n > 1)
    foreign = sorted(set(seen) - set(expected))
    problems = [f"{len(found)} episode(s) {what}: {named(found)}" for found, what in
                ((missing, "missing (an unfinished shard? finish it with eval --resume)"),
                 (doubled, "in more than one shard"), (foreign, "not of this run"))
                if found]
    if problems:
        raise MergeError("cannot merge: " + "; ".join(problems))
    order = {episode: index for index, episode in enumerate(expected)}
    records.sort(key=lambda record: order[record["episode"]])
    check_out(out)
    with run_lock(out):
        prepare(out, options.to_json(), resume=False)
        (out / RESULTS).write_text("".join(json_line(r) for r in records), encoding="utf-8")
        result = summary(with_motion(records, {e.id: e.motion for e in episodes}), options)
        write_json_atomic(out / SUMMARY, result)
        write_scores(out / SCORES, records)
    write_report(out)
    return result
