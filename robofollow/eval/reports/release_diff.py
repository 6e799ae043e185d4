"""`robofollow release diff A B` in words: per scene x level cell, the tasks and episodes
added, removed, changed and unchanged from release A to B (release.diff), and, for a policy's
runs on both, the parity table: each cell's scores on A and on B side by side, over all of its
episodes and over the unchanged ones only (where a deterministic policy must score alike)."""

from __future__ import annotations

from pathlib import Path

from robofollow import release
from robofollow.errors import RoboFollowError
from robofollow.eval.running.run_benchmark import run_release
from robofollow.eval.running.saved_run import load_options, load_records
from robofollow.eval.statistics.metrics import scores


class ReleaseDiffError(RoboFollowError):
    """Runs that are not of the releases diffed."""


def diff_markdown(a: str, b: str, rows: list[dict]) -> str:
    """The diff's table, a row per cell and one of totals."""
    lines = [f"## Release {a} -> {b}", "",
             "| Cell | Tasks added | removed | changed | unchanged | Episodes added | removed "
             "| changed | unchanged |", "|---|" + "---:|" * 8]
    totals = {kind: {k: 0 for k in ("added", "removed", "changed", "unchanged")}
              for kind in ("tasks", "episodes")}
    for row in rows:
        counts = [row[kind][k] for kind in ("tasks", "episodes") for k in totals[kind]]
        for kind in totals:
            for k in totals[kind]:
                totals[kind][k] += row[kind][k]
        lines.append(f"| {row['scene']} {row['level']} | " + " | ".join(map(str, counts)) + " |")
    lines.append("| **all** | " + " | ".join(
        f"**{totals[kind][k]}**" for kind in totals for k in totals[kind]) + " |")
    return "\n".join(lines) + "\n"


def _check_run(run: Path, name: str) -> list[dict]:
    """A run's records, refused unless it was made on release `name`."""
    made = run_release(load_options(run))
    if made != name:
        on = f"release {made}" if made else "a working compile"
        raise ReleaseDiffError(f"{run} was made on {on}, not release {name}: --runs takes a "
                               "run on each release, in the order of the releases")
    return load_records(run)


def parity_rows(rows: list[dict], run_a: Path, a: str, run_b: Path, b: str) -> list[dict]:
    """Per cell both runs hold: IS / ES / CR of run A (on release A) and run B (on B), over
    each run's episodes and over the episodes unchanged between the releases."""
    records_a, records_b = _check_run(run_a, a), _check_run(run_b, b)
    parity = []
    for row in rows:
        same = set(row["same"])
        cell = (row["scene"], row["level"])
        mine = [r for r in records_a if (r["scene"], r["level"]) == cell]
        theirs = [r for r in records_b if (r["scene"], r["level"]) == cell]
        if not mine or not theirs:
            continue
        both = {r["episode"] for r in mine} & {r["episode"] for r in theirs} & same
        parity.append({"scene": row["scene"], "level": row["level"],
                       "a": scores(mine), "b": scores(theirs),
                       "same_a": scores([r for r in mine if r["episode"] in both])
                       if both else None,
                       "same_b": scores([r for r in theirs if r["episode"] in both])
                       if both else None})
    return parity


def _shown(value: dict | None, metric: str) -> str:
    return "-" if value is None else f"{value[metric]:.1f}"


def parity_markdown(parity: list[dict], run_a: Path, run_b: Path) -> str:
    """The parity table: IS and CR per cell on both releases, and on their unchanged
    episodes."""
    lines = [f"## Parity: {run_a} (A) and {run_b} (B)", "",
             "| Cell | IS A | IS B | CR A | CR B | Unchanged episodes | IS A | IS B | CR A "
             "| CR B |", "|---|" + "---:|" * 9]
    for row in parity:
        episodes = row["same_a"]["episodes"] if row["same_a"] else 0
        lines.append(
            f"| {row['scene']} {row['level']} | {_shown(row['a'], 'IS')} | "
            f"{_shown(row['b'], 'IS')} | {_shown(row['a'], 'CR')} | {_shown(row['b'], 'CR')} "
            f"| {episodes} | {_shown(row['same_a'], 'IS')} | {_shown(row['same_b'], 'IS')} | "
            f"{_shown(row['same_a'], 'CR')} | {_shown(row['same_b'], 'CR')} |")
    return "\n".join(lines) + "\n"


def release_diff(a: str, b: str, runs: tuple[Path, Path] | None = None) -> str:
    """The diff of releases A and B as markdown, with the parity table of `runs` (a run on A,
    a run on B) where given."""
    rows = release.diff(release.load(a), release.load(b))
    text = diff_markdown(a, b, rows)
    if runs:
        text += "\n" + parity_markdown(parity_rows(rows, runs[0], a, runs[1], b), *runs)
    return text
