"""Writing a build to its folder:

    episodes/<scene>_<level>.jsonl   one episode per line (task x round, with its seed)
    tasks/<scene>_<level>.jsonl      one test task per line, with its goal DAG and expert plan
    rejected.jsonl                   every rejected candidate, with the reason
    audit.json                       entropy, groups, counts, leakage, repertoire, ambiguity
    summary.txt                      the same, for people

Deterministic: same specs, same bytes. A build replaces the one in its folder whole: it is
written to a temporary sibling folder and renamed into place once complete, so a failure (a
full disk) leaves the previous build as it was and nothing half-written. A folder that holds
anything else is refused.
"""

from __future__ import annotations

import errno
import os
import secrets
import shutil
from pathlib import Path

from robofollow.benchmark.labels import labels
from robofollow.benchmark.pipeline import Compiled
from robofollow.benchmark.rounds import episode_lines
from robofollow.benchmark.summary import changes, summary
from robofollow.compiler.planning.goals import goal_graph, graph_to_dict
from robofollow.compiler.planning.plans import plan
from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.compiler.scene.spec import LEVELS, Scene
from robofollow.compiler.scene.world import World
from robofollow.errors import RoboFollowError
from robofollow.files import json_line, json_lines, read_file_at_most

MAX_TASKS_FILE_BYTES = 64 * 1024 * 1024  # a build's tasks/SCENE_LEVEL.jsonl: the largest of the
#   built-in benchmark's, scene3_L3.jsonl, takes 340 KB


def _line(record: dict) -> str:
    return json_line(record, sort_keys=True)


def _task_ids(out: Path) -> set[str]:
    """The test task ids of the build in `out`, if there is one (files and lines that cannot
    be read as tasks are passed over: this is a report, not a check)."""
    ids = set()
    for path in sorted((out / "tasks").glob("*.jsonl")) if (out / "tasks").is_dir() else ():
        data, problem = read_file_at_most(path, MAX_TASKS_FILE_BYTES)
        if problem:
            continue
        ids.update(str(line.value["task"]) for line in json_lines(data)
                   if isinstance(line.value, dict) and "task" in line.value)
    return ids


class OutputError(RoboFollowError):
    """An output folder that cannot take a build, or a build that could not be written."""

    code = "output"


BUILD_FILES = ("audit.json", "rejected.jsonl", "summary.txt")  # beside episodes/ and tasks/
BUILD_FOLDERS = ("episodes", "tasks")  # of .jsonl files


def _entries(folder: Path | str) -> dict[str, os.DirEntry]:
    with os.scandir(folder) as entries:
        return {entry.name: entry for entry in entries}


def _is_build(folder: Path) -> bool:
    """Whether a folder holds a build and nothing else (what `write` may replace whole)."""
    entries = _entries(folder)
    if "audit.json" not in entries or not set(entries) <= {*BUILD_FILES, *BUILD_FOLDERS}:
        return False
    for name, entry in entries.items():
        if name in BUILD_FILES and not entry.is_file(follow_symlinks=False):
            return False
        if name in BUILD_FOLDERS:
            if not entry.is_dir(follow_symlinks=False):
                return False
            if not all(inner.endswith(".jsonl") and found.is_file(follow_symlinks=False)
                       for inner, found in _entries(entry.path).items()):
                return False
    return True


def _target(out: Path) -> Path:
    """The folder a build goes to: `out`, or where it links to."""
    return Path(os.path.realpath(out)) if out.is_symlink() else out


def check_out(out: Path) -> None:
    """Refuse, before any work, an output folder that cannot take a build: a file, a folder
    that holds something other than a previous build, a read-only folder, or a path that
    cannot be created (a file on the way, no permission)."""
    target = _target(out)
    try:
        if target.exists():
            if not target.is_dir():
                raise OutputError(f"--out {out} is a file, not a folder")
            if _entries(target) and not _is_build(target):
                raise OutputError(
                    f"--out {out} is not empty and does not hold a previous build (only "
                    "episodes/, tasks/, audit.json, rejected.jsonl and summary.txt); a build "
                    "replaces its folder whole, so choose an empty or a new folder")
            if not os.access(target, os.W_OK | os.X_OK):
                raise OutputError(f"--out {out} is read-only")
            if os.path.ismount(target):  # the build is made inside it (see _replace_inside)
                return
        elif out.is_symlink():
            raise OutputError(f"--out {out} is a symbolic link to nothing")
        parent = target.parent
        while not parent.exists() and parent != parent.parent:
            if parent.is_symlink():
                raise OutputError(f"--out {out} cannot be made: {parent} is a symbolic link "
                                  "to nothing")
            parent = parent.parent
        if not parent.is_dir():
            raise OutputError(f"--out {out} cannot be made: {parent} is a file, not a folder")
        if not os.access(parent, os.W_OK | os.X_OK):
            raise OutputError(f"--out {out} cannot be made: {parent} is read-only")
    except OSError as error:
        raise OutputError(f"--out {out}: {error.strerror or error}") from None


def _make_parents(folder: Path) -> list[Path]:
    """Create a folder and its missing parents; the folders created, outermost first."""
    missing = []
    while not folder.exists():
        missing.append(folder)
        folder = folder.parent
    for path in reversed(missing):
        path.mkdir()
    return list(reversed(missing))


def write(compiled: Compiled, out: Path) -> str:
    """Write every output file under `out` (created if needed), replacing the build there
    whole once the new one is complete; what changed against that build, in words. On an
    OSError (a full disk) nothing is left half-written: the previous build stays, and an
    OutputError says what failed."""
    check_out(out)
    target = _target(out)
    changed = changes(_task_ids(target) if target.is_dir() else set(), compiled)
    inside = target.is_dir() and os.path.ismount(target)  # cannot be renamed: build inside it
    where = target if inside else target.parent
    partial = where / f".{target.name}.partial-{os.getpid()}-{secrets.token_hex(4)}"
    created: list[Path] = []
    try:
        created = _make_parents(target.parent)
        partial.mkdir()
        _write_files(compiled, partial, changed)
        (_replace_inside if inside else _replace)(partial, target)
    except BaseException as error:  # a full disk, or Ctrl-C: nothing half-written stays
        shutil.rmtree(partial, ignore_errors=True)
        for folder in reversed(created):
            try:
                folder.rmdir()
            except OSError:
                break
        if not isinstance(error, OSError):
            raise
        reason = error.strerror or str(error)
        if error.errno == errno.ENOSPC:
            reason = "no space left on the device"
        raise OutputError(f"cannot write the build to {out}: {reason}; nothing was written "
                          "there") from None
    return changed


def _replace(partial: Path, target: Path) -> None:
    """Rename the complete new build into place; the old one is removed only then."""
    if not target.exists():
        os.rename(partial, target)
        return
    old = target.parent / f".{target.name}.old-{os.getpid()}-{secrets.token_hex(4)}"
    os.rename(target, old)
    try:
        os.rename(partial, target)
    except OSError:
        os.rename(old, target)
        raise
    shutil.rmtree(old, ignore_errors=True)


def _replace_inside(partial: Path, target: Path) -> None:
    """The same for a folder that is a mount point (it cannot be renamed): the complete new
    build, made inside it, takes the old one's place entry by entry."""
    old = target / f".old-{os.getpid()}-{secrets.token_hex(4)}"
    old.mkdir()
    moved: list[str] = []
    placed: list[str] = []
    try:
        for name in sorted(set(os.listdir(target)) - {partial.name, old.name}):
            os.rename(target / name, old / name)
            moved.append(name)
        for name in sorted(os.listdir(partial)):
            os.rename(partial / name, target / name)
            placed.append(name)
    except OSError:
        for name in placed:
            os.rename(target / name, partial / name)
        for name in moved:
            os.rename(old / name, target / name)
        old.rmdir()
        raise
    partial.rmdir()
    shutil.rmtree(old, ignore_errors=True)


def _write_files(compiled: Compiled, out: Path, changed: str) -> None:
    (out / "episodes").mkdir()
    (out / "tasks").mkdir()
    for scene in compiled.spec.scenes:
        goals_and_plans = _GoalsAndPlans(compiled.spec.scenes[scene])
        for level in LEVELS:
            tasks = compiled.splits.of(scene, level)
            with open(out / "episodes" / f"{scene}_{level}.jsonl", "w", encoding="utf-8") as f:
                for task in tasks:
                    f.writelines(line for _, line in episode_lines(compiled, task))
            with open(out / "tasks" / f"{scene}_{level}.jsonl", "w", encoding="utf-8") as f:
                for task in tasks:
                    goal, points = goals_and_plans.of(task.behaviour, task.layout)
                    f.write(_line({"task": task.id, "origin": task.origin,
                                   "wording": task.wording, "layout": task.layout,
                                   "instruction": task.instruction,
                                   **labels(goals_and_plans.scene, task, compiled.training),
                                   "goal": goal, "plan": points}))
    with open(out / "rejected.jsonl", "w", encoding="utf-8") as f:
        f.writelines(_line(r.model_dump(mode="json")) for r in compiled.splits.rejected)
    (out / "audit.json").write_text(compiled.audit_json, encoding="utf-8")
    (out / "summary.txt").write_text(summary(compiled, changed), encoding="utf-8")


class _GoalsAndPlans:
    """A scene's goal DAGs and expert plans as the task files hold them, each made once (a
    reworded task asks for its origin's behaviour on its origin's layout)."""

    def __init__(self, scene: Scene):
        self.scene = scene
        self.worlds: dict[str, World] = {}
        self.made: dict[tuple[str, str], tuple[dict, list]] = {}

    def of(self, behaviour: Behaviour, layout: str) -> tuple[dict, list]:
        key = behaviour.model_dump_json(), layout
        if key not in self.made:
            if layout not in self.worlds:
                self.worlds[layout] = World(self.scene, layout)
            self.made[key] = (graph_to_dict(goal_graph(behaviour)),
                              plan(behaviour, self.worlds[layout]).model_dump(
                                  mode="json")["points"])
        return self.made[key]
