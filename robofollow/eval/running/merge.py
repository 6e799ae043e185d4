"""`robofollow merge`: the shards of one run (`eval --shard I/N`, e.g. the tasks of a job
array) joined into a run like any other. The shards must be the N parts of one run (the same
options but the shard, the same specs) and hold, together, every episode of the run exactly
once, and the same control arms; otherwise nothing is written and the error names what is
missing, doubled or different. The merged run records every environment its shards ran in."""

from __future__ import annotations

import os
import shutil
import sys
from collections import Counter
from dataclasses import replace
from pathlib import Path

from robofollow.benchmark.episode import Episode
from robofollow.compiled_cache import Episodes
from robofollow.errors import RoboFollowError, named
from robofollow.eval.running.run_folder import (
    CONTROLS,
    LOCK,
    RESULTS,
    RUN_FILE,
    SCORES,
    SUMMARY,
    EvalOutputError,
    check_out,
    control_arms,
    present,
    run_lock,
    safe_path,
    write_file,
)
from robofollow.eval.running.runner import (
    EvalOptions,
    select_episodes,
    shard_of,
    summary,
    with_motion,
)
from robofollow.eval.running.saved_run import load_provenance, load_run
from robofollow.eval.running.scores import scores_bytes
from robofollow.files import (
    differing_options,
    json_bytes,
    json_line,
    json_value,
    read_file_at_most,
)
from robofollow.provenance import differences


class MergeError(RoboFollowError):
    """Shards that do not make one run."""


def _whole(shards: list[Path], loaded: list[tuple[EvalOptions, list[dict]]],
           episodes: int) -> EvalOptions:
    """The options of the run the shards are parts of, once they are checked to be its N
    parts (N at most its `episodes`)."""
    whole = replace(loaded[0][0], shard=None)
    parts = []
    for shard, (options, _) in zip(shards, loaded, strict=True):
        if options.shard is None:
            raise MergeError(f"{shard} is a whole run, not a shard (eval --shard I/N makes one)")
        if replace(options, shard=None) != whole:
            differ = differing_options(replace(options, shard=None).to_json(),
                                       whole.to_json())
            raise MergeError(f"{shard} was run with other options than {shards[0]} "
                             f"({', '.join(differ)} differ): shards of one run share them")
        parts.append(shard_of(options.shard, episodes))
        arms = control_arms(shard)
        if arms != list(options.controls):
            raise MergeError(f"{shard} holds the control arms {', '.join(arms) or 'none'} but "
                             f"was run with {', '.join(options.controls) or 'none'}: its "
                             "run.json and its controls/ folder disagree")
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


def _provenance(shards: list[Path]) -> list[dict]:
    """Every environment that ran a shard, once each, in the shards' order; said by name
    where they differ."""
    made = list({json_value(entry): entry for shard in shards
                 for entry in load_provenance(shard)}.values())
    for entry in made[1:]:
        print(f"warning: the shards ran in different environments "
              f"({'; '.join(differences(made[0], entry))}): their trajectory hashes are not "
              "all comparable with one environment's", file=sys.stderr)
    return made


def merge(benchmark: Episodes, shards: list[Path], out: Path) -> tuple[dict, list[Path]]:
    """Join the shards into the run folder `out` (new), and each of their control arms into
    out/controls/<mode>; returns the run's summary and the folders written, the run last (its
    report reads its arms'). Everything is checked before anything is written, and the run is
    written whole into the scratch folder .OUT.merging beside `out`, then moved there: a merge
    stopped part-way leaves `out` as it was, and the same command finishes it (a folder that
    holds this merge already is left as it is)."""
    loaded = [load_run(shard) for shard in shards]
    if loaded[0][0].spec_digest != benchmark.spec.digest:
        raise MergeError("the shards were run on other specs than these (--specs chooses the "
                         "run's)")
    episodes = select_episodes(benchmark, replace(loaded[0][0], shard=None))  # (every arm's)
    options = _whole(shards, loaded, len(episodes))
    arms = [(out, shards, loaded, options)]
    for mode in options.controls:
        arm_shards = [shard / CONTROLS / mode for shard in shards]
        arm_loaded = [load_run(shard) for shard in arm_shards]
        arm = _whole(arm_shards, arm_loaded, len(episodes))
        if arm != options.arm(mode):
            raise MergeError(f"{arm_shards[0]} is not the {mode} control arm of the shards' run")
        arms.append((safe_path(out, CONTROLS, mode), arm_shards, arm_loaded, arm))
    written = [(arm_out, *_contents(arm_shards, arm_options,
                                    *_joined(episodes, arm_loaded, arm_out)))
               for arm_out, arm_shards, arm_loaded, arm_options in arms]
    if all(_holds(arm_out, files) for arm_out, files, _ in written):
        print(f"{out} already holds this merge: nothing is written", file=sys.stderr)
    else:
        _check_new(out)
        scratch = safe_path(out.parent, f".{out.name}.merging")
        with run_lock(scratch), run_lock(out):
            _check_new(out)  # (again, held: another command may have written it meanwhile)
            _clear(scratch)
            for arm_out, files, _ in written:
                _write(scratch / arm_out.relative_to(out), files)
            _move(scratch, out)
    return written[0][2], [arm_out for arm_out, *_ in written[::-1]]


def _check_new(out: Path) -> None:
    """A merged run goes to a new folder (or an empty one)."""
    check_out(out)
    if present(out / RUN_FILE):
        raise MergeError(f"{out} already holds a run; merge writes a new run: choose another "
                         "--out")


def _clear(scratch: Path) -> None:
    """Empty the scratch folder of a merge that was stopped part-way (its lock kept: held)."""
    for entry in scratch.iterdir():
        if entry.name == LOCK:
            continue
        if entry.is_dir() and not entry.is_symlink():
            shutil.rmtree(entry)
        else:
            entry.unlink()


def _move(scratch: Path, out: Path) -> None:
    """The merged run, whole, into `out`, which holds at most what a new run's folder may
    (check_out: its lock, held here, and writes a kill left unfinished), removed first."""
    try:
        for leftover in out.iterdir():
            leftover.unlink()
        out.rmdir()
        os.rename(scratch, out)
    except OSError as error:
        raise EvalOutputError(f"cannot move the merged run from {scratch} to {out}: "
                              f"{error.strerror or error}; merge again to finish") from None


def _joined(episodes: list[Episode], loaded: list[tuple[EvalOptions, list[dict]]],
            out: Path) -> tuple[list[dict], dict[str, str | None]]:
    """One arm's records from its shards, in the run's episode order, checked to hold every
    episode once; and each episode's motion."""
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
        raise MergeError(f"cannot merge into {out}: " + "; ".join(problems))
    order = {episode: index for index, episode in enumerate(expected)}
    records.sort(key=lambda record: order[record["episode"]])
    return records, {e.id: e.motion for e in episodes}


def _contents(shards: list[Path], options: EvalOptions, records: list[dict],
              motions: dict[str, str | None]) -> tuple[dict[str, bytes], dict]:
    """One arm's files, from its joined records, and its summary."""
    result = summary(with_motion(records, motions), options)
    files = {RUN_FILE: json_bytes(dict(options.to_json(), provenance=_provenance(shards))),
             RESULTS: "".join(json_line(r) for r in records).encode(),
             SUMMARY: json_bytes(result), SCORES: scores_bytes(records)}
    return files, result


def _holds(out: Path, files: dict[str, bytes]) -> bool:
    """Whether a folder holds these files already (a merge stopped after it moved them in)."""
    for name, data in files.items():
        found, problem = read_file_at_most(out / name, len(data))
        if problem or found != data:
            return False
    return True


def _write(out: Path, files: dict[str, bytes]) -> None:
    for name, data in files.items():
        write_file(safe_path(out, name), data)
