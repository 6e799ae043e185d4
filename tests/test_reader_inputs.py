"""Every file RoboFollow reads, in a run folder or outside one, goes through a validating reader: a file
that is not a regular file (a FIFO, a link to a device, a folder) or is too large, and a JSON
file with a value of the wrong type in a field, is refused with one line that names the file
(exit status 1 or 2): never a traceback, a hang or unbounded memory.

READERS is the list of those readers: for each, how to make a valid input in a temporary
folder, the file to damage, and the command that reads it. A new reader is one more row."""

from __future__ import annotations

import fnmatch
import io
import json
import os
import resource
import shutil
import subprocess
import sys
import time
import zipfile
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from robofollow import trajectory
from robofollow.audit.task_list import read_task_list
from robofollow.benchmark.splits_lock import read_lock
from robofollow.cli import main
from robofollow.data import lerobot_v30
from robofollow.data.check import check
from robofollow.data.generate import _manifest
from robofollow.data.lerobot import EXTRA_EPISODE_FIELDS, VIDEO_KEYS
from robofollow.errors import RoboFollowError
from robofollow.eval.running.run_folder import read_results, summarised_episodes
from robofollow.eval.running.saved_run import read_run_file
from robofollow.learn import checkpoint
from robofollow.learn.demos import read_demonstrations
from robofollow.learn.train import resumed_options
from robofollow.resources import builtin_specs
from robofollow.vqa.grade import grade
from tests.cli_helpers import run

ROOT = Path(__file__).resolve().parent.parent
BASELINE = ROOT / "robofollow" / "baselines" / "scene2-blind"
TASK = "pickup_left_cube"  # the training task of the generated dataset
EPISODE = "scene2/L0/pickup_left_cube"  # a test task evaluated
TIMEOUT_S = 60  # a command that reads a FIFO it should refuse hangs past this
MEMORY_BYTES = 2 << 30  # RLIMIT_DATA of a command: each command here passes under it with its
#   valid input (eval, the largest, holds 0.4 GiB), a read of the 3 GiB file cannot. (RLIMIT_AS
#   would not do: eval's address space peaks at 1.7 GiB, train's at 2.3, mostly reserved.)
OVERSIZED = 3 << 30  # bytes of the sparse file that stands for a file too large to read


# -- the damage done to a reader's file -------------------------------------------------------

def _oversized(path: Path) -> None:
    with open(path, "wb"):
        os.truncate(path, OVERSIZED)


DAMAGES: dict[str, Callable[[Path], None]] = {
    "oversized": _oversized,
    "fifo": os.mkfifo,
    "device": lambda path: path.symlink_to("/dev/zero"),
    "folder": Path.mkdir,
}


def _damaged(path: Path, damage: str) -> None:
    """`path`, a file, replaced by the damage."""
    path.unlink()
    DAMAGES[damage](path)


# -- valid inputs -------------------------------------------------------------------------------

class Inputs:
    """What several rows build on, made once a module: a generated dataset (LeRobot v2.1, one
    demonstration of TASK; and as v3.0 and HDF5), a finished run and the expert's trajectory
    of EPISODE."""

    def __init__(self, folder: Path):
        self.folder = folder

    @cached_property
    def dataset(self) -> Path:
        return self._generate("dataset")

    @cached_property
    def v30(self) -> Path:
        """The same demonstration as a LeRobot v3.0 dataset, of small images."""
        return self._generate("v30", "--format", "lerobot-v3.0", "--image-size", "32x24")

    @cached_property
    def hdf5(self) -> Path:
        """The same demonstration as an HDF5 dataset, of small images."""
        return self._generate("hdf5", "--format", "hdf5", "--image-size", "32x24")

    def _generate(self, name: str, *options: str) -> Path:
        out = self.folder / name
        assert main(["generate", "--out", str(out), "--tasks", TASK, "--episodes-per-task", "1",
                     "--workers", "1", "--quiet", *options]) == 0
        return out

    @cached_property
    def run(self) -> Path:
        """A finished run of two episodes, with its full records."""
        out = self.folder / "run"
        assert main(["eval", "--policy", "noop", "--tasks", EPISODE, "--rounds", "2",
                     "--workers", "1", "--quiet", "--out", str(out)]) == 0
        return out

    @cached_property
    def trajectory(self) -> Path:
        path = self.folder / "trajectory.npz"
        assert main(["expert", "--episode", f"{EPISODE}#r1", "--trajectory", str(path),
                     "--image-size", "32x24", "--specs", str(builtin_specs())]) == 0
        return path


def _checkpoint(tmp: Path) -> Path:
    folder = tmp / "ckpt"
    shutil.copytree(BASELINE, folder)
    return folder


def _in_checkpoint(name: str):
    """A row's input: a copy of a shipped checkpoint, whose `name` eval reads."""
    def make(tmp: Path, inputs: Inputs) -> tuple[Path, list[str]]:
        folder = _checkpoint(tmp)
        return folder / name, ["eval", "--policy", str(folder), "--out", str(tmp / "run"),
                               "--tasks", EPISODE, "--rounds", "1", "--workers", "1", "--quiet"]
    return make


def _optimizer(tmp: Path, inputs: Inputs) -> tuple[Path, list[str]]:
    """A shipped checkpoint as if trained on the generated dataset, with its optimizer state:
    `train --resume` reads the dataset, then the optimizer state."""
    dataset, folder = _copy(inputs.dataset, tmp / "dataset"), _checkpoint(tmp)
    meta = json.loads((folder / "policy.json").read_text())
    meta["training"]["options"]["dataset"] = str(dataset)
    (folder / "policy.json").write_text(json.dumps(meta))
    loaded = checkpoint.load(folder)
    moments = {f"{moment}.{name}": np.zeros_like(value) for name, value in loaded.params.items()
               for moment in ("first", "second")}
    checkpoint.save(folder, loaded, {"step": np.array(1), **moments})
    return folder / "optimizer.npz", ["train", str(dataset), "--out", str(folder), "--resume",
                                      "--no-cache", "--quiet"]


def _resumed(tmp: Path, inputs: Inputs) -> tuple[Path, list[str]]:
    """_optimizer's checkpoint, whose policy.json `train --resume` reads its training record
    from: the options and the wall time spent."""
    path, argv = _optimizer(tmp, inputs)
    return path.parent / "policy.json", argv


TASK_LINE = {"id": "a", "scene": "scene2", "level": "L2", "layout": "default",
             "instruction": "Use your left arm to pick up the blue cylinder and place it in the "
                            "rightmost bowl."}


def _task_list(tmp: Path, inputs: Inputs) -> tuple[Path, list[str]]:
    path = tmp / "tasks.jsonl"
    path.write_text(json.dumps(TASK_LINE) + "\n")
    return path, ["audit", str(builtin_specs()), "--tasks", str(path)]


def _splits_lock(tmp: Path, inputs: Inputs) -> tuple[Path, list[str]]:
    specs = tmp / "specs"
    specs.mkdir()
    shutil.copy(builtin_specs() / "scene2.rf", specs)
    shutil.copy(builtin_specs() / "splits.lock", specs)
    return specs / "splits.lock", ["compile", str(specs), "--out", str(tmp / "build"),
                                   "--no-verify"]


def _copy(source: Path, target: Path) -> Path:
    shutil.copytree(source, target)
    return target


def _train(dataset: Path, tmp: Path) -> list[str]:
    return ["train", str(dataset), "--out", str(tmp / "ckpt"), "--policy", "blind",
            "--cameras", "cam_high", "--no-cache", "--quiet"]


def _meta_only(tmp: Path, inputs: Inputs) -> Path:
    """The dataset's meta/info.json and meta/episodes.jsonl alone: training reads them, then
    stops at the missing frames."""
    dataset = tmp / "dataset"
    (dataset / "meta").mkdir(parents=True)
    for name in ("info.json", "episodes.jsonl"):
        shutil.copy(inputs.dataset / "meta" / name, dataset / "meta" / name)
    return dataset


def _training_file(name: str):
    """A row's input: a copy of the dataset, whose `name` training reads."""
    def make(tmp: Path, inputs: Inputs) -> tuple[Path, list[str]]:
        dataset = (_meta_only(tmp, inputs) if name.startswith("meta/") else
                   _copy(inputs.dataset, tmp / "dataset"))
        return dataset / name, _train(dataset, tmp)
    return make


def _checked_file(name: str, version: str = "v2.1"):
    """A row's input: a copy of the dataset (the HDF5 one where `version` is "hdf5"; as v3.0
    where it is "v3.0": its info.json and meta/tasks.parquet) whose `name` `dataset check`
    reads."""
    def make(tmp: Path, inputs: Inputs) -> tuple[Path, list[str]]:
        dataset = _copy(inputs.hdf5 if version == "hdf5" else inputs.dataset, tmp / "dataset")
        if version == "v3.0":
            info = json.loads((dataset / "meta" / "info.json").read_text())
            (dataset / "meta" / "info.json").write_text(json.dumps(
                {**info, "codebase_version": "v3.0", "data_path": lerobot_v30.DATA_PATH,
                 "video_path": lerobot_v30.VIDEO_PATH}))
            pq.write_table(pa.table({"task": ["a"], "task_index": [0]}),
                           dataset / "meta" / "tasks.parquet")
        return dataset / name, ["dataset", "check", str(dataset)]
    return make


def _unit(tmp: Path, inputs: Inputs) -> tuple[Path, list[str]]:
    """A generation interrupted once its one unit was recorded (the unit made again from the
    dataset): `generate --resume` writes the dataset from the unit's arrays.npz."""
    dataset, out = inputs.dataset, tmp / "out"
    unit = out / ".work" / "units" / TASK / "0000"
    unit.mkdir(parents=True)
    manifest = json.loads((dataset / "manifest.json").read_text())
    (out / ".work" / "options.json").write_text(json.dumps(manifest["options"]))
    record = json.loads((dataset / "meta" / "episodes.jsonl").read_text())
    stats = json.loads((dataset / "meta" / "episodes_stats.jsonl").read_text())["stats"]
    images = {key: {name: value[0] if name == "count" else [v[0][0] for v in value]
                    for name, value in stats[key].items()} for key in VIDEO_KEYS}
    (unit / "demo.json").write_text(json.dumps({**manifest["demos"][0], **record,
                                                "image_stats": images}))
    frames = pq.read_table(dataset / FRAMES)
    np.savez(unit / "arrays.npz", **{
        name: np.array(frames.column(column).to_pylist(), np.float32)
        for name, column in (("state", "observation.state"), ("action", "action"),
                             ("environment_state", "observation.environment_state"))})
    for key in VIDEO_KEYS:
        shutil.copy(dataset / f"videos/chunk-000/{key}/episode_000000.mp4", unit / f"{key}.mp4")
    return unit / "arrays.npz", _resume_generation(out)


def _resume_generation(out: Path) -> list[str]:
    return ["generate", "--out", str(out), "--resume", "--tasks", TASK, "--episodes-per-task",
            "1", "--workers", "1", "--quiet"]


def _generated(name: str):
    """A row's input: a generation of the dataset's options, complete (`name` manifest.json)
    or interrupted (.work/options.json; a unit's .work/units/.../demo.json), that `generate
    --resume` reads."""
    def make(tmp: Path, inputs: Inputs) -> tuple[Path, list[str]]:
        out = tmp / "out"
        manifest = json.loads((inputs.dataset / "manifest.json").read_text())
        (out / name).parent.mkdir(parents=True)
        if name != "manifest.json":
            (out / ".work" / "options.json").write_text(json.dumps(manifest["options"]))
        if name != ".work/options.json":
            (out / name).write_text(json.dumps(manifest))
        return out / name, _resume_generation(out)
    return make


ANSWER = {"id": "q1", "prediction": "red", "question": "What colour is the cube?",
          "expected": {"type": "color", "color": "red", "object": None, "needs_color": False,
                       "objects": [], "sides": [], "question_names": [], "template": "colour"}}


def _answers(tmp: Path, inputs: Inputs) -> tuple[Path, list[str]]:
    path = tmp / "answers.jsonl"
    path.write_text(json.dumps(ANSWER) + "\n")
    return path, ["vqa", "score", str(path)]


def _trajectory(tmp: Path, inputs: Inputs) -> tuple[Path, list[str]]:
    path = Path(shutil.copy(inputs.trajectory, tmp / "trajectory.npz"))
    return path, ["score", str(path), "--specs", str(builtin_specs())]


def _in_run(name: str, how: str = "report"):
    """A row's input: a copy of the finished run, whose `name` `report` reads (`how`:
    "scores only", of the run keeping only its scores, as the shipped ones do; "resume",
    `eval --resume` of the run made unfinished, its summary gone)."""
    def make(tmp: Path, inputs: Inputs) -> tuple[Path, list[str]]:
        run = _copy(inputs.run, tmp / "run")
        if how == "scores only":
            (run / "episodes.jsonl").unlink()
        if how != "resume":
            return run / name, ["report", str(run)]
        (run / "summary.json").unlink()
        return run / name, ["eval", "--policy", "noop", "--tasks", EPISODE, "--rounds", "2",
                            "--workers", "1", "--quiet", "--out", str(run), "--resume"]
    return make


def _previous_build(tmp: Path, inputs: Inputs) -> tuple[Path, list[str]]:
    """A folder that holds a build (as `compile` may replace it): its task files are read for
    what changed."""
    build = tmp / "build"
    (build / "tasks").mkdir(parents=True)
    (build / "audit.json").write_text("{}")
    (build / "tasks" / "scene2_L1.jsonl").write_text('{"task": "scene2/L1/a"}\n')
    return build / "tasks" / "scene2_L1.jsonl", [
        "compile", str(builtin_specs() / "scene2.rf"), "--out", str(build), "--no-verify"]


# -- the readers ----------------------------------------------------------------------------

@dataclass(frozen=True)
class Reader:
    """A reader of a file outside a run folder, as a command reaches it."""

    name: str
    make: Callable[[Path, Inputs], tuple[Path, list[str]]]  # (tmp, inputs) -> (the file, the
    #   command that reads it), a valid input made in tmp
    damages: tuple[str, ...] = tuple(DAMAGES)  # those that reach the reader
    named: str | None = None  # how the command names the file, where not by its path
    report: bool = False  # the command reports the file on standard output, not as an error
    passes_over: bool = False  # a file it cannot read is passed over: the command goes on
    read: Callable[[Path], object] | None = None  # JSON readers: the function that reads the
    #   file, for the fields of any value (`free`); every other field is checked for its type
    free: tuple[str, ...] = ()  # fnmatch patterns of those fields' paths ("a.b", "a.0")


def _read_demonstrations(path: Path):
    """The dataset whose meta/ folder holds `path`, read without its cameras."""
    return read_demonstrations(path.parent.parent, (), 1)


# the fields of meta/info.json that training does not read
INFO_NOT_READ = ("robot_type", "total_*", "data_path", "splits", "splits.*", "features.*")

# the fields of a checkpoint's training record that `train --resume` does not read
TRAINING_NOT_READ = tuple(f"training.{name}" for name in (
    "episodes", "val_episodes", "frames", "cores", "steps", "val_loss", "loss"))

# the fields of meta/info.json that `dataset check` does not check: LeRobot leaves them free
# (and the null names of a scalar feature, whose other type here is an object, as LeRobot's
# names may be)
CHECK_INFO_NOT_READ = ("robot_type", "splits", "splits.*", "features.*.info", "features.*.info.*",
                       "features.*.names.*", "features.timestamp.names", "features.*index.names")
FRAMES = "data/chunk-000/episode_000000.parquet"  # the dataset's one episode's frames


def _dataset_check(path: Path) -> None:
    """`dataset check` of the dataset whose meta/ folder holds `path`: its findings raised."""
    report = check(path.parent.parent)
    if not report.ok:
        raise RoboFollowError("; ".join(report.errors))


SUMMARY_NOT_READ = ("policy", "instruction_mode", "observed", "splits", "splits.*", "cells",
                    "cells.*", "avg", "avg.*", "references", "references.*",
                    "policy_failures", "policy_failures.*")  # a report recomputes the summary:
#   of summary.json it reads the episodes counted only (to refuse a results file cut short)

READERS = [
    Reader("run.json", _in_run("run.json"), read=lambda path: read_run_file(path.parent)),
    Reader("run.json on resume", _in_run("run.json", "resume"),
           read=lambda path: read_run_file(path.parent)),
    Reader("summary.json", _in_run("summary.json"),
           read=lambda path: summarised_episodes(path.parent), free=SUMMARY_NOT_READ),
    Reader("episodes.jsonl", _in_run("episodes.jsonl"), read=read_results),
    Reader("episodes.jsonl on resume", _in_run("episodes.jsonl", "resume"), read=read_results),
    Reader("scores.csv.gz", _in_run("scores.csv.gz", "scores only")),
    Reader("checkpoint policy.json", _in_checkpoint("policy.json"),
           read=lambda path: checkpoint.load(path.parent),
           free=("training.*",)),  # recorded (train --resume reads its options)
    Reader("checkpoint params.npz", _in_checkpoint("params.npz")),
    Reader("checkpoint optimizer.npz", _optimizer),
    Reader("train --resume policy.json", _resumed,
           damages=(),  # (checkpoint.load reads it, damaged: "checkpoint policy.json")
           read=lambda path: resumed_options(path.parent, path.parent.parent / "dataset", {}),
           free=TRAINING_NOT_READ),
    Reader("task list", _task_list, read=read_task_list),
    Reader("splits.lock", _splits_lock, read=read_lock),
    Reader("training meta/info.json", _training_file("meta/info.json"),
           read=_read_demonstrations, free=INFO_NOT_READ),
    Reader("training meta/episodes.jsonl", _training_file("meta/episodes.jsonl"),
           read=_read_demonstrations, free=("scene", "layout", "seed", "spec_digest")),
    Reader("training frames", _training_file(FRAMES)),
    Reader("training video", _training_file(
        "videos/chunk-000/observation.images.cam_high/episode_000000.mp4")),
    Reader("dataset check JSON", _checked_file("meta/info.json"), named="info.json",
           report=True, read=_dataset_check, free=CHECK_INFO_NOT_READ),
    Reader("dataset check JSON Lines", _checked_file("meta/episodes.jsonl"),
           named="episodes.jsonl", report=True, read=_dataset_check,
           free=EXTRA_EPISODE_FIELDS),  # RoboFollow's own, beside LeRobot's
    Reader("dataset check parquet", _checked_file("meta/tasks.parquet", "v3.0"),
           named="meta/tasks.parquet", report=True),
    # (of the damages, those that pyarrow and h5py do not refuse themselves: pyarrow reads a
    #   folder as a dataset of parquet files, h5py waits on a FIFO)
    Reader("dataset check frames", _checked_file(FRAMES), damages=("folder",), named=FRAMES,
           report=True),
    Reader("dataset check HDF5", _checked_file("data/episode_000000.hdf5", "hdf5"),
           damages=("fifo", "folder"), named="data/episode_000000.hdf5", report=True),
    Reader("generate manifest.json", _generated("manifest.json"),
           read=lambda path: _manifest(path.parent),
           free=("generator", "demos", "demos.*", "options.*")),
    #   (options.*: compared with the command's own; a difference is refused, naming --out)
    Reader("generate options.json", _generated(".work/options.json")),
    # a unit's demo.json that is not a regular file is not taken for one: it is recorded again
    Reader("generate demo.json", _generated(f".work/units/{TASK}/0000/demo.json"),
           damages=("oversized",)),
    Reader("generate arrays.npz", _unit,
           damages=("oversized", "fifo", "device")),  # (np.load refuses a folder itself)
    Reader("vqa answers", _answers, read=grade,
           free=("prediction", "question")),  # an answer in any form; shown as given
    Reader("trajectory", _trajectory),
    # a build's files that are not regular files make its folder one compile does not replace
    Reader("previous build's tasks", _previous_build, damages=("oversized",),
           passes_over=True),
]
BY_NAME = {reader.name: reader for reader in READERS}


@pytest.fixture(scope="module")
def inputs(tmp_path_factory) -> Inputs:
    return Inputs(tmp_path_factory.mktemp("inputs"))


def _limited() -> None:
    """A command's memory bounded (its preexec_fn)."""
    resource.setrlimit(resource.RLIMIT_DATA, (MEMORY_BYTES, MEMORY_BYTES))


class Commands:
    """Commands run in processes of their own, AT_ONCE at a time in the order they are queued,
    each under TIMEOUT_S and MEMORY_BYTES, their output in files of their folder; all started
    from this thread (preexec_fn is not safe in threads)."""

    def __init__(self):
        self.queued: dict[object, tuple[list[str], Path]] = {}
        self.running: dict[object, tuple[subprocess.Popen, Path, float]] = {}
        self.done: dict[object, subprocess.CompletedProcess | None] = {}  # None: ran too long

    def queue(self, key, argv: list[str], cwd: Path) -> None:
        self.queued[key] = argv, cwd

    def result(self, key) -> subprocess.CompletedProcess:
        """The command's outcome, once it has run (the next ones running meanwhile)."""
        while key not in self.done:
            while self.queued and len(self.running) < AT_ONCE:
                self._start(next(iter(self.queued)))
            if not self._reaped():
                time.sleep(0.05)
        done = self.done.pop(key)
        if done is None:
            pytest.fail(f"{key}: the command ran past {TIMEOUT_S} s")
        return done

    def _start(self, key) -> None:
        argv, cwd = self.queued.pop(key)
        with open(cwd / "stdout", "w") as out, open(cwd / "stderr", "w") as err:
            process = subprocess.Popen([sys.executable, "-m", "robofollow.cli", *argv],
                                       cwd=cwd, env={**os.environ, "PYTHONPATH": str(ROOT)},
                                       preexec_fn=_limited, stdout=out, stderr=err)
        self.running[key] = process, cwd, time.monotonic()

    def _reaped(self) -> bool:
        """Whether a command ended (or was ended, past TIMEOUT_S)."""
        for key, (process, cwd, began) in self.running.items():
            if process.poll() is None and time.monotonic() - began < TIMEOUT_S:
                continue
            if process.returncode is None:
                process.kill()
                process.wait()
                self.done[key] = None
            else:
                self.done[key] = subprocess.CompletedProcess(
                    process.args, process.returncode, (cwd / "stdout").read_text(),
                    (cwd / "stderr").read_text())
            del self.running[key]
            return True
        return False

    def stop(self) -> None:
        for process, _, _ in self.running.values():
            process.kill()
            process.wait()


DAMAGE_TEST = "test_a_damaged_file_is_refused_in_one_line"
CASES = [pytest.param(reader.name, damage, id=f"{reader.name}-{damage}")
         for reader in READERS for damage in reader.damages]
AT_ONCE = 2  # commands run side by side: each spends seconds importing, on a core of its own


@pytest.fixture(scope="module")
def cases(request, inputs, tmp_path_factory) -> Iterator[tuple[dict, Commands]]:
    """The damaged file of each case this run selects, by (reader, damage), and the commands
    that read them, queued in the tests' order."""
    commands, damaged = Commands(), {}
    for item in request.session.items:
        if getattr(item, "originalname", None) == DAMAGE_TEST:
            key = item.callspec.params["name"], item.callspec.params["damage"]
            folder = tmp_path_factory.mktemp("case")
            path, argv = BY_NAME[key[0]].make(folder, inputs)
            _damaged(path, key[1])
            damaged[key] = path
            commands.queue(key, argv, folder)
    yield damaged, commands
    commands.stop()


@pytest.mark.parametrize("name, damage", CASES)
def test_a_damaged_file_is_refused_in_one_line(cases, name, damage):
    (damaged, commands), reader = cases, BY_NAME[name]
    done = commands.result((name, damage))
    assert "Traceback" not in done.stdout + done.stderr, done.stderr
    if reader.passes_over:
        assert done.returncode == 0, done.stderr
        return
    assert done.returncode in (1, 2), (done.returncode, done.stdout, done.stderr)
    named = reader.named or str(damaged[name, damage])
    if reader.report:
        assert _one_finding(done.stdout, named), done.stdout
    else:
        assert done.stderr.count("\n") == 1 and named in done.stderr, done.stderr


def _one_finding(report: str, named: str) -> bool:
    """Whether one finding of a command's report, and one only, names the file."""
    return [named in line for line in report.splitlines()].count(True) == 1


# -- a value of the wrong type in every field ---------------------------------------------------

def _wrong(value):
    """A value of another JSON type: a list for a string, a string for a number or a bool, a
    number for a list or an object, an object for null."""
    if isinstance(value, str):
        return ["wrong"]
    if isinstance(value, bool | int | float):
        return "wrong"
    if isinstance(value, list | dict):
        return 7
    return {"wrong": 1}


def _replaced(container, key, value):
    if isinstance(container, dict):
        return {**container, key: value}
    return [value if index == key else item for index, item in enumerate(container)]


def variants(document) -> Iterator[tuple[str, object]]:
    """("field.path", the document with that field's value of another type), for the document
    itself ("") and every field in it (a list's first item stands for the others)."""
    yield "", _wrong(document)
    yield from _inner(document, ())


def _inner(value, path: tuple[str, ...]) -> Iterator[tuple[str, object]]:
    items = (value.items() if isinstance(value, dict) else
             list(enumerate(value))[:1] if isinstance(value, list) else ())
    for key, item in items:
        where = (*path, str(key))
        yield ".".join(where), _replaced(value, key, _wrong(item))
        for deeper, changed in _inner(item, where):
            yield deeper, _replaced(value, key, changed)


def _write(path: Path, document, rest: list[str]) -> None:
    """The file with `document` as its JSON (its first line, before `rest`, for JSON Lines)."""
    path.write_text("".join([json.dumps(document) + "\n", *rest]))


JSON_READERS = [reader.name for reader in READERS if reader.read is not None]


@pytest.mark.parametrize("name", JSON_READERS)
def test_a_value_of_the_wrong_type_is_refused_in_one_line(tmp_path, inputs, capsys, name):
    reader = BY_NAME[name]
    path, _ = reader.make(_folder(tmp_path, "valid"), inputs)
    lines = path.read_text().splitlines(keepends=True)
    document = json.loads(lines[0] if path.suffix == ".jsonl" else "".join(lines))
    _reads(reader, path, "")  # the valid file reads
    free, refused = [], []
    for number, (where, changed) in enumerate(variants(document)):
        path, argv = reader.make(_folder(tmp_path, str(number)), inputs)
        _write(path, changed, lines[1:] if path.suffix == ".jsonl" else [])
        if _matched(where, reader.free):
            free.append(where)
            _reads(reader, path, where)
            continue
        refused.append(where)
        status, out, err = run(capsys, *argv)
        if reader.report:
            assert status == 1 and _one_finding(out, reader.named), (where, out, err)
        else:
            assert status in (1, 2) and err.count("\n") == 1 and str(path) in err, (where, err)
    unused = [pattern for pattern in reader.free if not any(_matched(w, (pattern,)) for w in free)]
    assert refused and not unused, (refused, unused)


V30_ROWS = "meta/episodes/chunk-000/file-000.parquet"


def test_a_v30_episode_row_of_the_wrong_type_is_one_finding(tmp_path, inputs):
    """The v3.0 episode table's columns (statistics apart: check_stats reads any value), each
    of another type in turn: `dataset check` names the table once, or passes over a column it
    does not read."""
    table = pq.read_table(inputs.v30 / V30_ROWS)
    assert check(inputs.v30).ok
    free = (*EXTRA_EPISODE_FIELDS, "meta/episodes/*")  # (LeRobot's index of the row's file)
    for index, name in enumerate(table.column_names):
        if name.startswith("stats/"):
            continue
        wrong = [7 if pa.types.is_string(table.schema.field(name).type) else "wrong"]
        root = _copy(inputs.v30, tmp_path / str(index))
        pq.write_table(table.set_column(index, name, pa.array(wrong * table.num_rows)),
                       root / V30_ROWS)
        errors = check(root).errors
        if _matched(name, free):
            assert not errors, (name, errors)
        else:
            assert [e.startswith("meta/episodes") for e in errors].count(True) == 1, (name, errors)


def _matched(where: str, patterns: tuple[str, ...]) -> bool:
    return any(fnmatch.fnmatchcase(where, pattern) for pattern in patterns)


def _folder(tmp_path: Path, name: str) -> Path:
    (tmp_path / name).mkdir()
    return tmp_path / name


def _reads(reader: Reader, path: Path, where: str) -> None:
    """The reader reads the file: whatever it raises is about another file."""
    try:
        reader.read(path)
    except RoboFollowError as error:
        assert (reader.named or str(path)) not in str(error), (where, str(error))


@pytest.mark.parametrize("expected, field", [
    ({"type": "object"}, "expected.object"),
    ({"type": "color"}, "expected.color"),
    ({"type": "sides"}, "expected.objects"),
    ({"type": "sides", "objects": [{"color": "red", "kind": "cube"}]}, "expected.sides"),
])
def test_an_expected_answer_without_what_its_type_names_is_refused(tmp_path, capsys, expected,
                                                                   field):
    path = tmp_path / "answers.jsonl"
    path.write_text(json.dumps({**ANSWER, "expected": expected}) + "\n")
    status, _, err = run(capsys, "vqa", "score", str(path))
    assert status == 1 and err.count("\n") == 1 and f"{path}:1: {field} is" in err, err


# -- archives whose arrays claim more than they may hold ---------------------------------------

def _npz(path: Path, members: dict[str, bytes]) -> Path:
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, data in members.items():
            archive.writestr(f"{name}.npy", data)
    return path


def _claiming(shape: tuple[int, ...]) -> bytes:
    """A .npy file's header alone, for float64 values of `shape`."""
    stream = io.BytesIO()
    np.lib.format.write_array_header_1_0(stream, {"descr": "<f8", "fortran_order": False,
                                                  "shape": shape})
    return stream.getvalue()


def test_an_optimizer_state_whose_arrays_claim_too_much_is_refused_unread(tmp_path):
    _npz(tmp_path / "optimizer.npz", {"first.w": _claiming((1 << 57,)), "step": _claiming(())})
    with pytest.raises(checkpoint.CheckpointError) as caught:
        checkpoint.load_optimizer(tmp_path)
    assert str(caught.value).startswith(f"{tmp_path / 'optimizer.npz'}: cannot resume")
    assert "more than the" in str(caught.value)


def test_a_trajectory_that_unpacks_past_the_limit_is_refused_unread(tmp_path, monkeypatch):
    monkeypatch.setattr(trajectory, "MAX_TRAJECTORY_BYTES", 1 << 20)
    path = _npz(tmp_path / "bomb.npz", {"time": bytes(2 << 20)})
    with pytest.raises(trajectory.TrajectoryError, match="its arrays unpack to more than 1 MiB"):
        trajectory.Trajectory.load(path)


def test_a_trajectory_whose_arrays_claim_too_much_is_one_error(tmp_path):
    names = ("bodies", "meta", *trajectory._ARRAYS)
    path = _npz(tmp_path / "claims.npz", {name: _claiming((1 << 57,)) for name in names})
    with pytest.raises(trajectory.TrajectoryError,
                       match=r"cannot read a trajectory \((MemoryError|ValueError)"):
        trajectory.Trajectory.load(path)


@pytest.mark.parametrize("version", ["v2.1", "v3.0"])
@pytest.mark.parametrize("key", ["data_path", "video_path"])
def test_a_path_template_with_unknown_fields_is_one_finding(tmp_path, inputs, version, key):
    """A path template of info.json that names a field the check does not fill in (a
    KeyError traceback) is one finding naming it."""
    root = _copy(inputs.dataset if version == "v2.1" else inputs.v30, tmp_path / "dataset")
    info = json.loads((root / "meta" / "info.json").read_text())
    (root / "meta" / "info.json").write_text(json.dumps({**info, key: "{nope}/{0}.parquet"}))
    errors = check(root).errors
    assert [e.startswith(f"meta/info.json: {key} is ") for e in errors].count(True) == 1, errors
