"""`robofollow generate`: expert demonstrations of the training tasks as a dataset.

Two phases. Recording: each job (task, episode index) becomes a unit folder under
`OUT/.work/units/`, written atomically by a pool of workers (one simulation and renderer
each); an interrupted run (even kill -9) keeps every finished unit and `--resume` records only
the rest. Writing: the dataset files are built from the units in job order, so the result does
not depend on which worker finished first or on interruptions; `manifest.json` is written last
and the work folder removed.
"""

from __future__ import annotations

import os
import shutil
import time
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

from tqdm import tqdm

from robofollow.benchmark.episode import Benchmark
from robofollow.data import hdf5_export, lerobot_v21, lerobot_v30
from robofollow.data.jobs import DemoJob, demo_jobs
from robofollow.data.units import Options, UnitRecorder, read_record, unit_path
from robofollow.errors import RoboFollowError
from robofollow.files import changed_options, number_problem, shown, write_json_atomic
from robofollow.workers import results

WRITERS = {"lerobot-v2.1": lerobot_v21.write, "lerobot-v3.0": lerobot_v30.write,
           "hdf5": hdf5_export.write}
WORK = ".work"
MANIFEST = "manifest.json"
DATASET_ENTRIES = ("meta", "data", "videos", "episodes.jsonl", "info.json", MANIFEST)


class GenerateError(RoboFollowError):
    """The output folder cannot be used as asked (not empty, other options...)."""


@dataclass
class GenerateResult:
    out: Path
    episodes: int
    demonstrations: int
    recorded: int  # units recorded by this run (the rest came from an interrupted one)
    discarded: int  # attempts the oracle rejected, over all demonstrations
    failed: list[dict] = field(default_factory=list)
    seconds: float = 0.0
    already_complete: bool = False


def _check_folder(out: Path, options: Options, resume: bool) -> None:
    """Refuse to mix datasets: a fresh run needs an empty folder, a resumed one the same
    options as the run it continues."""
    occupied = out.is_dir() and any(out.iterdir())
    if not resume:
        if occupied:
            raise GenerateError(f"{out} is not empty; pass --resume to continue an interrupted "
                                "run there, or choose another folder")
        return
    previous = _previous_options(out)
    if previous is None:
        if occupied:
            raise GenerateError(f"{out} holds files but no RoboFollow generation to resume")
        return
    problem = changed_options(previous, options.to_json())
    if problem:
        raise GenerateError(f"{out} {problem}")


def _previous_options(out: Path) -> dict | None:
    """The options of the generation in `out`: an interrupted one's (.work/options.json), else
    a complete one's (its manifest); None where there is neither."""
    recorded = out / WORK / "options.json"
    if os.path.lexists(recorded):
        return read_record(recorded)
    return _manifest(out)["options"] if os.path.lexists(out / MANIFEST) else None


COUNTS = ("episodes", "demonstrations", "discarded_attempts")  # of the manifest: whole numbers


def _manifest(out: Path) -> dict:
    """manifest.json, with the fields generate reads (options, COUNTS, failed) checked."""
    path = out / MANIFEST
    manifest = read_record(path)
    problem = _manifest_problem(manifest)
    if problem:
        raise GenerateError(f"{path}: {problem}")
    return manifest


def _manifest_problem(manifest: dict) -> str | None:
    if not isinstance(manifest.get("options"), dict):
        return f"options is {shown(manifest.get('options'))}, not an object"
    for key in COUNTS:
        if not isinstance(manifest.get(key), int) or number_problem(manifest[key], 0):
            return f"{key} is {shown(manifest.get(key))}, not a whole number from 0"
    failed = manifest.get("failed")
    if not (isinstance(failed, list) and all(isinstance(job, dict) and
                                             isinstance(job.get("failed"), str)
                                             for job in failed)):
        return f"failed is {shown(failed)}, not a list of failed jobs"
    return None


# -- recording -----------------------------------------------------------------------------

def _record_all(compiled: Benchmark, options: Options, work: Path,
                jobs: list[DemoJob], workers: int, progress: bool) -> list[dict]:
    todo = [job for job in jobs if not (unit_path(work, job) / "demo.json").is_file()]
    bar = tqdm(total=len(jobs), initial=len(jobs) - len(todo), desc="recording", unit="demo",
               disable=not progress, smoothing=0.1)
    failed = []
    # the compiled benchmark travels pickled to pool workers (~50 ms), not recompiled
    with bar:
        for result in results(partial(UnitRecorder, compiled, options, work), todo, workers):
            failed += [result] if "failed" in result else []
            bar.update()
    return failed


# -- writing -------------------------------------------------------------------------------

def _clear_dataset(out: Path) -> None:
    for name in DATASET_ENTRIES:
        path = out / name
        if path.is_dir():
            shutil.rmtree(path)
        elif path.exists():
            path.unlink()


def _write(out: Path, options: Options, jobs: list[DemoJob], failed: list[dict],
           recorded: int, progress: bool) -> GenerateResult:
    work = out / WORK
    demos = []
    for job in jobs:
        unit = unit_path(work, job)
        if (unit / "demo.json").is_file():
            demos.append((read_record(unit / "demo.json"), unit))
    _clear_dataset(out)
    per_demo = [1 if options.format == "hdf5" else len(d["instructions"]) for d, _ in demos]
    with tqdm(total=sum(per_demo), desc="writing", unit="episode", disable=not progress) as bar:
        episodes = WRITERS[options.format](out, demos, options.width, options.height, bar.update)
    first = 0
    listing = []
    for (demo, _), count in zip(demos, per_demo, strict=True):
        listing.append({"label": demo["label"], "index": demo["index"], "seed": demo["seed"],
                        "length": demo["length"], "episodes": list(range(first, first + count)),
                        "instructions": demo["instructions"], "discarded": demo["discarded"]})
        first += count
    discarded = sum(len(d["discarded"]) for d, _ in demos)
    manifest = {"generator": "robofollow generate", "options": options.to_json(),
                "episodes": episodes, "demonstrations": len(demos),
                "discarded_attempts": discarded, "failed": failed, "demos": listing}
    write_json_atomic(out / MANIFEST, manifest)
    shutil.rmtree(work)
    return GenerateResult(out, episodes, len(demos), recorded, discarded, failed)


def generate(compiled: Benchmark, out: Path, options: Options, workers: int = 1,
             resume: bool = False, progress: bool = True) -> GenerateResult:
    """Record (or finish recording) the demonstrations and write the dataset."""
    began = time.perf_counter()
    if options.spec_digest != compiled.spec.digest:
        raise GenerateError("the options' spec digest is not the compiled specs' digest")
    _check_folder(out, options, resume)
    work = out / WORK
    if (out / MANIFEST).is_file() and not work.exists():
        manifest = _manifest(out)
        return GenerateResult(out, manifest["episodes"], manifest["demonstrations"], 0,
                              manifest["discarded_attempts"], manifest["failed"],
                              already_complete=True)
    shutil.rmtree(work / "tmp", ignore_errors=True)  # half-written units of a killed run
    work.mkdir(parents=True, exist_ok=True)
    write_json_atomic(work / "options.json", options.to_json())
    jobs = demo_jobs(compiled, options.episodes_per_task, list(options.tasks),
                     options.instructions)
    done_before = sum((unit_path(work, job) / "demo.json").is_file() for job in jobs)
    failed = _record_all(compiled, options, work, jobs, workers, progress)
    recorded = sum((unit_path(work, job) / "demo.json").is_file() for job in jobs) - done_before
    result = _write(out, options, jobs, failed, recorded, progress)
    result.seconds = time.perf_counter() - began
    return result
