"""The split lock: each scene's split digest and task counts, pinned in `splits.lock` beside
the specs, so that a change to a published split is reported by name and task count, never
silent. `robofollow compile` compares every scene with the lock (and verifies the scenes that
differ in simulation); `robofollow compile --update-lock` writes it."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from robofollow.benchmark.pipeline import Compiled
from robofollow.compiler.scene.spec import LEVELS
from robofollow.errors import RoboFollowError
from robofollow.files import write_json_atomic

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


def read_lock(path: Path | None) -> dict[str, dict]:
    """The pinned scenes ({} when there is no lock file)."""
    if path is None or not path.is_file():
        return {}
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        scenes = data["scenes"]
        if not all(isinstance(v, dict) and isinstance(v.get("split"), str)
                   for v in scenes.values()):
            raise ValueError("every scene needs a 'split' digest")
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as error:
        raise RoboFollowError(f"{path}: not a split lock ({error}); rewrite it with "
                              "`robofollow compile SPECS --out DIR --update-lock`") from None
    return scenes


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
