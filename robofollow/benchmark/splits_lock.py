"""The split lock: each scene's split digest and task counts, pinned in `splits.lock` beside
the specs, so that a change to a published split is reported by name and task count, never
silent. `robofollow compile` compares every scene with the lock (and verifies the scenes that
differ in simulation); `robofollow compile --update-lock` writes it."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from robofollow.benchmark.compiled import Compiled
from robofollow.compiler.scene.spec import LEVELS
from robofollow.errors import RoboFollowError
from robofollow.files import read_json_file, write_json_atomic

LOCK_FILE = "splits.lock"


def lock_entries(compiled: Compiled) -> dict[str, dict]:
    """{scene: {"split": digest, "tasks": {level: count}}} for every compiled scene."""
    return {scene: {"split": digest,
                    "tasks": {level: len(compiled.splits.of(scene, level)) for level in LEVELS}}
            for scene, digest in compiled.split_digests.items()}


def lock_path(specs: Path | list[Path]) -> Path | None:
    """The lock beside the specs: in a specs folder, or in a spec file's folder (None for a
    list of files)."""
    if not isinstance(specs, Path):
        return None
    return (specs if specs.is_dir() else specs.parent) / LOCK_FILE


MAX_LOCK_BYTES = 1024 * 1024  # the shipped lock is under 1 KB


def _lock_problem(data) -> str | None:
    """What is wrong with a lock's content: {"scenes": {scene: {"split": digest, "tasks":
    {level: count}}}}."""
    scenes = data.get("scenes") if isinstance(data, dict) else None
    if not isinstance(scenes, dict):
        return "no \"scenes\" object"
    for scene, entry in scenes.items():
        if not isinstance(entry, dict) or not isinstance(entry.get("split"), str):
            return f"scene {scene!r} needs a 'split' digest"
        tasks = entry.get("tasks", {})
        if not isinstance(tasks, dict) or not all(
                level in LEVELS and isinstance(n, int) and not isinstance(n, bool) and n >= 0
                for level, n in tasks.items()):
            return f"scene {scene!r}: 'tasks' must map levels ({', '.join(LEVELS)}) to counts"
    return None


def read_lock(path: Path | None) -> dict[str, dict]:
    """The pinned scenes ({} when there is no lock file); RoboFollowError for a lock that is
    not a regular file, is too large, or is not a split lock."""
    if path is None or not (path.exists() or path.is_symlink()):
        return {}
    data, problem = (None, "not a regular file") if not path.is_file() else \
        read_json_file(path, MAX_LOCK_BYTES)
    problem = problem or _lock_problem(data)
    if problem:
        raise RoboFollowError(f"{path}: not a split lock ({problem}); rewrite it with "
                              "`robofollow compile SPECS --out DIR --update-lock`")
    return data["scenes"]


def write_lock(path: Path, compiled: Compiled) -> None:
    write_json_atomic(path, {"scenes": lock_entries(compiled)})


@dataclass(frozen=True)
class LockCheck:
    same: tuple[str, ...]  # scenes whose split is the locked one
    changed: tuple[str, ...]  # scenes whose split differs from the locked one
    new: tuple[str, ...]  # scenes the lock does not pin
    lines: tuple[str, ...]  # what differs, one line per scene

    @property
    def unlocked(self) -> tuple[str, ...]:
        """The scenes to verify: changed or new."""
        return self.changed + self.new


def _counts(tasks: dict) -> str:
    return " ".join(f"{level} {tasks.get(level, 0)}" for level in LEVELS)


def check_lock(compiled: Compiled, locked: dict[str, dict]) -> LockCheck:
    """Every compiled scene against the lock."""
    same, changed, new, lines = [], [], [], []
    for scene, entry in lock_entries(compiled).items():
        pinned = locked.get(scene)
        if pinned is None:
            new.append(scene)
            lines.append(f"{scene}: new, not in {LOCK_FILE} ({_counts(entry['tasks'])})")
        elif pinned["split"] != entry["split"]:
            changed.append(scene)
            was = pinned.get("tasks", {})
            lines.append(f"{scene}: split CHANGED from {LOCK_FILE} ({pinned['split'][:12]} -> "
                         f"{entry['split'][:12]}; tasks {_counts(was)} -> "
                         f"{_counts(entry['tasks'])})")
        else:
            same.append(scene)
    return LockCheck(tuple(same), tuple(changed), tuple(new), tuple(lines))
