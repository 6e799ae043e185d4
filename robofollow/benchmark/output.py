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
from collections.abc import Iterable
from pathlib import Path

from robofollow.benchmark.compiled import Compiled
from robofollow.benchmark.summary import changes, summary
from robofollow.compiler.scene.spec import LEVELS
from robofollow.errors import RoboFollowError
from robofollow.files import json_lines, read_file_at_most

MAX_TASKS_FILE_BYTES = 64 * 1024 * 1024  # a build's tasks/SCENE_LEVEL.jsonl: the largest of the
#   built-in benchmark's, scene3_L3.jsonl, takes 340 KB


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


REJECTED = "rejected.jsonl"
BUILD_FILES = ("audit.json", REJECTED, "summary.txt")  # beside episodes/ and tasks/
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


def write(compiled: Compiled, out: Path, files: dict[str, str]) -> str:
    """Write the build under `out` (created if needed): `files` (`render.rendered`),
    audit.json and summary.txt, replacing the build there whole once the new one is
    complete; the summary written (`summary.summary`, with what changed against that build).
    On an OSError (a full disk) nothing is left half-written: the previous build stays, and
    an OutputError says what failed."""
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
        text = summary(compiled, changed)
        _write_files(compiled, partial, text, files)
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
    return text


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


def joined(parts: list[dict[str, str]]) -> dict[str, str]:
    """A benchmark's `render.rendered` files from those of its spec files compiled alone, in
    order: each scene's own files, and the rejections one part after the other."""
    files = {name: text for part in parts for name, text in part.items() if name != REJECTED}
    return files | {REJECTED: "".join(part[REJECTED] for part in parts)}


def episode_files(scenes: Iterable[str], ids: tuple[str, ...],
                  lines: tuple[bytes, ...]) -> dict[str, str]:
    """The episodes/ files of the scenes from their `episodes`."""
    files: dict[str, list[str]] = {f"episodes/{scene}_{level}.jsonl": []
                                   for scene in scenes for level in LEVELS}
    for episode, line in zip(ids, lines, strict=True):
        scene, level, _ = episode.split("/", 2)
        files[f"episodes/{scene}_{level}.jsonl"].append(line.decode() + "\n")
    return {name: "".join(texts) for name, texts in files.items()}


def _write_files(compiled: Compiled, out: Path, summary_text: str,
                 files: dict[str, str]) -> None:
    (out / "episodes").mkdir()
    (out / "tasks").mkdir()
    for name, text in files.items():
        (out / name).write_text(text, encoding="utf-8")
    (out / "audit.json").write_text(compiled.audit_json, encoding="utf-8")
    (out / "summary.txt").write_text(summary_text, encoding="utf-8")
