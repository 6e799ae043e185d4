"""Compile the benchmark: specs -> checked training tasks -> L0-L3 splits -> audit -> files.

Outputs (deterministic: same specs, same bytes):
    episodes/<scene>_<level>.jsonl   one episode per line (task x round, with its seed)
    tasks/<scene>_<level>.jsonl      one test task per line, with its goal DAG and expert plan
    rejected.jsonl                   every rejected candidate, with the reason
    audit.json                       entropy, groups, counts, leakage, repertoire, ambiguity
    summary.txt                      the same, for people

A build replaces the one in its folder whole: it is written to a temporary sibling folder and
renamed into place once complete, so a failure (a full disk) leaves the previous build as it
was and nothing half-written. A folder that holds anything else is refused.
"""

from __future__ import annotations

import difflib
import errno
import hashlib
import json
import os
import secrets
import shutil
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from robofollow.compiler import lf
from robofollow.compiler.behaviour import Behaviour
from robofollow.compiler.goals import goal_graph, graph_to_dict
from robofollow.compiler.plans import plan
from robofollow.compiler.spec import LEVELS, ROUNDS, Spec
from robofollow.compiler.spec_loader import load_partial, spec_files
from robofollow.compiler.splits import Splits, TestTask, episode_seed, generate
from robofollow.compiler.training import training_behaviours
from robofollow.compiler.world import World
from robofollow.files import json_line
from robofollow.errors import RoboFollowError, SpecErrors
from robofollow.audit.splits import FINDING_KEYS, audit, findings
from robofollow.audit.task_list import listed_tests


@dataclass
class Compiled:
    spec: Spec
    splits: Splits
    report: dict
    training: dict[str, Behaviour]  # every training task's behaviour, by label

    def candidates(self, scene: str) -> dict[str, Behaviour]:
        """The scene's training behaviours by label: what 'did instead' is matched against."""
        return {t.label: self.training[t.label] for t in self.spec.scenes[scene].tasks}


def compile_specs(specs: Path | list[Path]) -> Compiled:
    """Load, check, generate and audit; raises SpecErrors on bad specs."""
    if isinstance(specs, Path):
        return _compile_cached(Path(os.path.realpath(specs)), _mtimes(specs))
    return _compile(specs)


def _mtimes(folder: Path) -> tuple:
    """The state of every spec file the compile reads (the cache key)."""
    state = []
    for file in spec_files(folder):
        try:
            info = os.stat(file)
        except OSError:
            continue
        state.append((str(file), info.st_mtime_ns, info.st_size, info.st_ino))
    return tuple(state)


@lru_cache(maxsize=4)
def _compile_cached(specs: Path, _mtimes: tuple) -> Compiled:
    """One compile per specs folder and file state, per process (compiled results are frozen)."""
    return _compile(specs)


def _compile(specs: Path | list[Path]) -> Compiled:
    """Every error of the specs in one report: loading, training tasks, listed tests (the
    checks of tasks on layouts that failed to load are skipped rather than repeated)."""
    loaded = load_partial(specs)
    if loaded.spec is None:
        raise SpecErrors(loaded.errors)
    spec = loaded.spec
    training, training_errors = training_behaviours(spec, loaded.suspect)
    listed, test_errors = listed_tests(spec, training, loaded.suspect)
    errors = loaded.errors + training_errors + test_errors
    if errors:
        raise SpecErrors(errors)
    splits = generate(spec, training)
    splits = splits.model_copy(update={"tasks": splits.tasks + listed})
    return Compiled(spec, splits, audit(spec, training, splits), training)


def _line(record: dict) -> str:
    return json_line(record, sort_keys=True)


def episodes(compiled: Compiled, task: TestTask) -> list[dict]:
    rule = compiled.spec.scenes[task.scene].splits.get(task.level)
    rounds, base = (rule.rounds, rule.seed) if rule else (ROUNDS, 42)
    form, behaviour = json.loads(lf.to_json(task.form)), task.behaviour.model_dump(mode="json")
    records = []
    for round_index in range(1, rounds + 1):
        record = {"episode": f"{task.id}#r{round_index}", "task": task.id, "scene": task.scene,
                  "level": task.level, "layout": task.layout, "instruction": task.instruction,
                  "lf": form, "behaviour": behaviour,
                  "round": round_index, "seed": episode_seed(task.id, round_index, base)}
        content = compiled.spec.digest + _line(record)
        record["hash"] = hashlib.sha256(content.encode()).hexdigest()[:16]
        records.append(record)
    return records


def all_episodes(compiled: Compiled) -> list[dict]:
    """Every episode of every level, in scene, level and task order."""
    return [record for scene in compiled.spec.scenes for level in LEVELS
            for task in compiled.splits.of(scene, level) for record in episodes(compiled, task)]


class UnknownEpisodeError(RoboFollowError):
    """An episode id that the compiled benchmark does not have."""


def find_episode(compiled: Compiled, episode_id: str) -> dict:
    """The episode with this id (`<scene>/<level>/<task>#r<round>`)."""
    task_id, _, _ = episode_id.partition("#")
    for task in compiled.splits.tasks:
        if task.id == task_id:
            for record in episodes(compiled, task):
                if record["episode"] == episode_id:
                    return record
    raise unknown_episode(episode_id, [t.id for t in compiled.splits.tasks])


def unknown_episode(episode_id: str, task_ids: list[str]) -> UnknownEpisodeError:
    """The error for an episode id the benchmark lacks, with the nearest task ids."""
    close = difflib.get_close_matches(episode_id.partition("#")[0], task_ids, n=3)
    hint = f"; did you mean {', '.join(c + '#r1' for c in close)}?" if close else ""
    return UnknownEpisodeError(f"no episode {episode_id!r} in the compiled benchmark (ids look "
                               f"like scene1/L0/pickup_yellow_block_2#r1){hint}")


def summary(compiled: Compiled, changes: str = "") -> str:
    report, spec = compiled.report, compiled.spec
    lines = [f"RoboFollow: {len(spec.scenes)} scenes, {len(spec.tasks)} training tasks, "
             f"spec digest {spec.digest[:12]}",
             f"scene entropy H(T|S) = {report['scene_entropy_bits']:.3f} bits over "
             f"{len(report['groups'])} training scene groups (task labels, as the paper counts); "
             f"over distinct behaviours H(B|S) = {report['behaviour_entropy_bits']:.3f} bits",
             "", "test tasks per scene and level (each run for the split's rounds):",
             "          " + "".join(f"{level:>6}" for level in LEVELS)]
    for scene, counts in report["counts"].items():
        lines.append(f"{scene:<10}" + "".join(f"{counts[level]:>6}" for level in LEVELS))
    lines += _rules_text(report["split_rules"])
    same = report["same_behaviour"]
    lines += ["", f"training tasks with the same behaviour on one layout: {len(same) or 'none'}"]
    lines += [f"  {item['layout']}: {', '.join(item['tasks'])}" for item in same]
    lines += ["", f"rejected candidates: {report['rejected']} (rejected.jsonl says why)"]
    for key in FINDING_KEYS:
        title = key.replace("_", " ")
        items = report[key]
        lines.append(f"{title}: {len(items) or 'none'}")
        lines += [f"  {item['task']}: {item['finding']}" for item in items[:20]]
    return "\n".join(lines) + "\n" + changes


def _rules_text(rules: dict) -> list[str]:
    """Tasks per layout, what each cap dropped and the rules' warnings, for people."""
    lines = ["", "test tasks per layout:"]
    for scene, levels in rules["layouts"].items():
        lines.append(f"  {scene:<12}" + "".join(f"{level:>6}" for level in LEVELS))
        for layout in dict.fromkeys(name for level in LEVELS for name in levels.get(level, {})):
            lines.append(f"    {layout:<10}" + "".join(
                f"{levels.get(level, {}).get(layout, '.'):>6}" for level in LEVELS))
    lines.append(f"caps: {'none applied' if not rules['capped'] else ''}".rstrip())
    lines += [f"  {c['scene']} {c['level']}: {c['kept']} kept (max {c['max']}), {c['dropped']} "
              "dropped ("
              + ", ".join(f"{layout} {n}" for layout, n in c["dropped_by_layout"].items()) + ")"
              for c in rules["capped"]]
    lines.append(f"split rule warnings: {len(rules['warnings']) or 'none'}")
    lines += [f"  {warning}" for warning in rules["warnings"]]
    return lines


def _task_ids(out: Path) -> set[str]:
    """The test task ids of the build in `out`, if there is one (lines that cannot be read as
    a task are passed over: this is a report, not a check)."""
    ids = set()
    for path in sorted((out / "tasks").glob("*.jsonl")) if (out / "tasks").is_dir() else ():
        try:
            with open(path, encoding="utf-8") as lines:
                for line in lines:
                    try:
                        ids.add(str(json.loads(line)["task"]))
                    except (ValueError, KeyError, TypeError):
                        continue
        except (OSError, UnicodeDecodeError):
            continue
    return ids


def changes(before: set[str], compiled: Compiled, shown: int = 20) -> str:
    """Which test tasks a build adds and removes against the ids of a previous one."""
    if not before:
        return ""
    after = {t.id for t in compiled.splits.tasks}
    added, removed = sorted(after - before), sorted(before - after)
    if not added and not removed:
        return "\nagainst the previous build: the same test tasks\n"
    lines = ["", f"against the previous build: {len(added)} test tasks added, {len(removed)} "
                 "removed"]
    lines += [f"  + {task}" for task in added[:shown]]
    lines += [f"  - {task}" for task in removed[:shown]]
    if max(len(added), len(removed)) > shown:
        lines.append(f"  (the first {shown} of each)")
    return "\n".join(lines) + "\n"


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
        for level in LEVELS:
            tasks = compiled.splits.of(scene, level)
            with open(out / "episodes" / f"{scene}_{level}.jsonl", "w", encoding="utf-8") as f:
                for task in tasks:
                    f.writelines(_line(r) for r in episodes(compiled, task))
            with open(out / "tasks" / f"{scene}_{level}.jsonl", "w", encoding="utf-8") as f:
                for task in tasks:
                    world = World(compiled.spec.scenes[scene], task.layout)
                    f.write(_line({"task": task.id, "origin": task.origin,
                                   "wording": task.wording, "layout": task.layout,
                                   "instruction": task.instruction,
                                   "goal": graph_to_dict(goal_graph(task.behaviour)),
                                   "plan": plan(task.behaviour, world).model_dump(
                                       mode="json")["points"]}))
    with open(out / "rejected.jsonl", "w", encoding="utf-8") as f:
        f.writelines(_line(r.model_dump(mode="json")) for r in compiled.splits.rejected)
    (out / "audit.json").write_text(json.dumps(compiled.report, indent=1, sort_keys=True) + "\n",
                                    encoding="utf-8")
    (out / "summary.txt").write_text(summary(compiled, changed), encoding="utf-8")


def clean(compiled: Compiled) -> bool:
    return findings(compiled.report) == 0
