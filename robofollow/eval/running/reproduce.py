"""`robofollow reproduce`: run recorded episodes of a finished run again and say what agrees.

Scores (Intent, Execution, completion, as the score file keeps them: four decimals) must
agree. Trajectory hashes (runner.trajectory_hash) agree bit for bit only where the arithmetic
is the same: where the run recorded its environment and this one matches it in every field of
provenance.ARITHMETIC, a differing hash is a failure; elsewhere the hashes are compared and
reported, and the fields that differ named. On another arithmetic (another CPU: NumPy's matrix
kernels differ) a learned policy's rollout drifts from the recorded one, and an episode near a
stage's threshold can score otherwise with it: the report then says that the environment
differs beside the scores that do."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

from robofollow.compiled_cache import Episodes
from robofollow.errors import RoboFollowError
from robofollow.eval.policies.policy_kind import is_trained, policy_kind
from robofollow.eval.running.runner import episode_records
from robofollow.eval.running.saved_run import load_records, read_run_file
from robofollow.learn.checkpoint import PREFIX, is_checkpoint
from robofollow.learn.policy import shipped_names
from robofollow.provenance import ARITHMETIC, differences, environment

DEFAULT_EPISODES = 8  # re-run by default: one per cell of two levels of four scenes


class ReproduceError(RoboFollowError):
    """A run that cannot be reproduced as asked."""


@dataclass
class Reproduction:
    """What re-running a run's episodes found."""

    run: str
    policy: str
    episodes: list[str]
    score_differences: list[str] = field(default_factory=list)  # "EPISODE: IS 0.5 / 0.6"
    hash_differences: list[str] = field(default_factory=list)  # episodes
    hashes_compared: int = 0  # episodes whose record carries a trajectory hash
    environment_differences: list[str] | None = None  # None: the run recorded none

    @property
    def environment_matches(self) -> bool:
        return self.environment_differences == []

    @property
    def agrees(self) -> bool:
        """Scores agree everywhere; hashes too where the environment matches."""
        return not self.score_differences and not (
            self.environment_matches and self.hash_differences)

    def text(self) -> str:
        count = len(self.episodes)
        scored = count - len(self.score_differences)
        lines = [(f"re-ran {count} recorded episode{'s' if count != 1 else ''} of {self.run} "
                  f"with {self.policy}:"),
                 f"  scores (Intent, Execution, completion): {scored} of {count} agree"]
        lines += [f"    {line}" for line in self.score_differences]
        agreeing = self.hashes_compared - len(self.hash_differences)
        if self.environment_differences is None:
            why = "the run records no environment, so they need not agree"
        elif self.environment_matches:
            why = "the recorded environment matches this one, so they must agree"
        else:
            why = ("the environment differs, so they need not agree: "
                   + "; ".join(self.environment_differences) + " (recorded / here)")
        lines.append(f"  trajectory hashes: {agreeing} of {self.hashes_compared} agree ({why})"
                     if self.hashes_compared else "  trajectory hashes: none recorded (the "
                     "records were written before runs kept them)")
        if self.environment_matches:
            lines += [f"    {episode}: another trajectory" for episode in self.hash_differences]
        lines.append("reproduced" if self.agrees else "NOT reproduced")
        return "\n".join(lines)


def sampled(records: list[dict], count: int) -> list[dict]:
    """`count` records spread over the run's scene x level cells: the cells in turn, each
    giving records evenly spaced over its own (in episode order)."""
    cells: dict[tuple[str, str], list[dict]] = {}
    for record in sorted(records, key=lambda r: r["episode"]):
        cells.setdefault((record["scene"], record["level"]), []).append(record)
    order = sorted(cells)
    taken = {cell: 0 for cell in order}
    for index in range(min(count, len(records))):
        open_cells = [cell for cell in order if taken[cell] < len(cells[cell])]
        taken[open_cells[index % len(open_cells)]] += 1
    return [cells[cell][(2 * k + 1) * len(cells[cell]) // (2 * taken[cell])]
            for cell in order for k in range(taken[cell])]


def _scores(record: dict) -> tuple[str, str, bool]:
    return (f"{record['intent_score']:.4f}", f"{record['execution_score']:.4f}",
            bool(record["complete"]))


def stand_in(run: Path, policy: str) -> str | None:
    """A shipped checkpoint for a run's checkpoint folder that is not here: the run's own
    (RUN/checkpoint, as a second seed ships), else the shipped baseline of the folder's name
    (`ckpt-NAME` or NAME: baseline:NAME); None when the policy is not such a folder or none
    ships. The re-run's scores say whether it is the one that made the run."""
    if policy_kind(policy) != "factory" or ":" in policy:  # (a folder that is not here)
        return None
    if is_checkpoint(run / "checkpoint"):
        return str(run / "checkpoint")
    name = Path(policy).name.removeprefix("ckpt-")
    return f"{PREFIX}{name}" if name in shipped_names() else None


def _check_episodes(run: Path, records: list[dict], benchmark: Episodes) -> None:
    """ReproduceError naming the first record whose episode the run's benchmark lacks, or
    whose recorded episode hash is not the benchmark's."""
    for record in records:
        episode = record["episode"]
        if episode not in benchmark.index:
            raise ReproduceError(f"{run}: episode {episode} is not in {_source(benchmark)}, "
                                 "the run's benchmark")
        recorded = record.get("hashes", {}).get("episode")
        if recorded and recorded != benchmark.record(episode).hash:
            raise ReproduceError(f"{run}: episode {episode} has hash {recorded} in the run "
                                 f"but {benchmark.record(episode).hash} in "
                                 f"{_source(benchmark)}: another episode under its id")


def _source(benchmark: Episodes) -> str:
    return f"release {benchmark.release}" if benchmark.release else "the working compile"


def reproduce(compiled: Episodes, run: Path, count: int = DEFAULT_EPISODES,
              policy: str | None = None, workers: int = 1,
              episodes: list[str] | None = None) -> Reproduction:
    """Run `count` of the run's recorded episodes again (or the named `episodes`) with its
    policy (or `policy`, e.g. a shipped baseline's name for a run made from its checkpoint
    folder) and compare them with the records. `compiled`: the run's benchmark
    (run_benchmark)."""
    options, made = read_run_file(run)
    if options.spec_digest != compiled.spec.digest:
        raise ReproduceError(f"{run} was run on other specs than these (--specs chooses the "
                             "run's)")
    recorded = load_records(run)
    if not recorded:
        raise ReproduceError(f"{run} records no episode: there is nothing to reproduce")
    if episodes is not None:
        by_id = {r["episode"]: r for r in recorded}
        unknown = [e for e in episodes if e not in by_id]
        if unknown:
            raise ReproduceError(f"{run} holds no episode {', '.join(unknown[:5])}")
        chosen = [by_id[e] for e in episodes]
    else:
        chosen = sampled(recorded, count)
    _check_episodes(run, chosen, compiled)
    options = replace(options, video="none", policy=policy or options.policy)
    here = environment(is_trained(options.policy))
    found = Reproduction(str(run), options.policy, [r["episode"] for r in chosen])
    if made:
        found.environment_differences = sorted(
            {line for entry in made for line in differences(entry, here, ARITHMETIC)})
    wanted = set(found.episodes)
    again = {r["episode"]: r for r in episode_records(
        compiled, options, run, compiled.episodes(lambda e: e in wanted), workers)}
    for record in chosen:
        other = again[record["episode"]]
        if _scores(record) != _scores(other):
            (a_is, a_es, a_cr), (b_is, b_es, b_cr) = _scores(record), _scores(other)
            found.score_differences.append(
                f"{record['episode']}: IS {a_is} / {b_is}, ES {a_es} / {b_es}, "
                f"complete {a_cr} / {b_cr} (recorded / again)")
        trajectory = record.get("hashes", {}).get("trajectory")
        if trajectory:
            found.hashes_compared += 1
            if trajectory != other["hashes"]["trajectory"]:
                found.hash_differences.append(record["episode"])
    return found
