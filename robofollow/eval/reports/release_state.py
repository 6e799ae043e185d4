"""The state of a folder of results: each run under it, the release it was made on, and whether
that is the current release ("current") or an older one ("on v1, to redo"), as a markdown table
made from the runs' run.json files alone (docs/results/state.md is this table of docs/results:
`robofollow release state docs/results --out docs/results/state.md`, checked by a test)."""

from __future__ import annotations

from pathlib import Path

from robofollow import release
from robofollow.errors import counted
from robofollow.eval.running.run_benchmark import run_release
from robofollow.eval.running.run_folder import RUN_FILE, present, summarised_episodes
from robofollow.eval.running.runner import EvalOptions
from robofollow.eval.running.saved_run import load_options


def runs_under(folder: Path) -> list[Path]:
    """Every run folder under `folder` (control arms included), in path order."""
    return sorted(path.parent for path in folder.rglob(RUN_FILE) if present(path))


def state(options: EvalOptions) -> tuple[str, str]:
    """(the run's benchmark, its state) from its options: ("v1", "current"), ("v1", "on v1,
    to redo") or ("working compile", "not a release: to redo on one")."""
    name = run_release(options)
    if name is None:
        return "working compile", "not a release: to redo on one"
    return name, "current" if name == release.CURRENT else f"on {name}, to redo"


def state_rows(folder: Path) -> list[dict]:
    """One row per run under `folder`: its path there, policy, instructions, episodes, release
    and state."""
    rows = []
    for run in runs_under(folder):
        options = load_options(run)
        made_on, now = state(options)
        rows.append({"run": run.relative_to(folder).as_posix(), "policy": options.policy,
                     "instructions": options.instruction_mode,
                     "episodes": summarised_episodes(run), "release": made_on, "state": now})
    return rows


def state_markdown(folder: Path, title: str | None = None) -> str:
    """The state table of the runs under `folder`, with a line that counts them."""
    rows = state_rows(folder)
    todo = sum(row["state"] != "current" for row in rows)
    lines = [f"# {title or 'State of the results in ' + folder.as_posix()}", "",
             f"Made by `robofollow release state {folder.as_posix()}` from the runs' "
             f"`run.json` files. The current release is {release.CURRENT}; "
             f"{counted(len(rows), 'run')}, {todo} to redo.", "",
             "| Run | Policy | Instructions | Episodes | Release | State |",
             "|---|---|---|---:|---|---|"]
    lines += [f"| `{row['run']}` | `{row['policy']}` | {row['instructions']} | "
              f"{'-' if row['episodes'] is None else format(row['episodes'], ',')} | "
              f"{row['release']} | {row['state']} |" for row in rows]
    return "\n".join(lines) + "\n"
