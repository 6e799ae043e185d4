"""Recording one demonstration job into a unit folder: the expert is run on the job's seeds in
turn until the oracle scores an attempt complete; the unit is written in a private temporary
folder and renamed into place, so a unit on disk is always whole.

A unit folder holds `demo.json` (seed, discarded attempts, length, instructions, image
statistics) and, for the LeRobot formats, `arrays.npz` (`state`, `action`: float32 (N, 14))
and one mp4 per camera; for HDF5, `episode.hdf5` with everything.
"""

from __future__ import annotations

import json
import os
import shutil
from contextlib import ExitStack
from dataclasses import asdict, dataclass
from pathlib import Path

import h5py
import numpy as np

from robofollow.benchmark.episode import Benchmark
from robofollow.compiler.scene.spec import Scene
from robofollow.data.jobs import MAX_ATTEMPTS, DemoJob
from robofollow.data.sinks import ArraySink, FrameSink, VideoSink
from robofollow.errors import RoboFollowError
from robofollow.files import read_json_object
from robofollow.sim import robot
from robofollow.sim.objects import objects_over
from robofollow.sim.rollout import ExpertRunner
from robofollow.sim.simulation import CONTROL_HZ
from robofollow.trajectory import Trajectory

ROBOT_TYPE = "aloha_agilex"  # upstream's robot_type, so existing ALOHA configs apply
MAX_RECORD_BYTES = 64 * 1024 * 1024  # a generation's JSON records: demo.json and
#   .work/options.json take about 1 KB, manifest.json about 400 bytes a demonstration (1.5 MB
#   for the benchmark's 3,750)


@dataclass(frozen=True)
class Options:
    """Everything that fixes a dataset's content; a resumed run must use the same."""
    format: str
    episodes_per_task: int
    tasks: tuple[str, ...]
    width: int
    height: int
    instructions: str
    spec_digest: str
    environment_state: bool = True  # the objects observation recorded (older runs: absent)

    def to_json(self) -> dict:
        return dict(asdict(self), tasks=list(self.tasks))


def dataset_arrays(trajectory: Trajectory, scene: Scene, layout: str) -> dict[str, np.ndarray]:
    """Observation t is the state (and the objects observation, flattened) before acting;
    action t is the joint target sent next (the recording's action at t + 1). The final
    observation has no action and is dropped."""
    objects = objects_over(trajectory, scene, layout)[:-1]
    return {"state": robot.observed_state(trajectory.state[:-1]),
            "environment_state": objects.reshape(len(objects), -1),
            "action": trajectory.action[1:].astype(np.float32)}


def unit_path(work: Path, job: DemoJob) -> Path:
    return work / "units" / job.key


class RecordError(RoboFollowError):
    """A generation's record (demo.json, options.json, manifest.json) that cannot be read."""


def read_record(path: Path) -> dict:
    """A JSON object file of at most MAX_RECORD_BYTES; else RecordError naming it."""
    data, problem = read_json_object(path, MAX_RECORD_BYTES)
    if problem:
        raise RecordError(f"{path}: {problem}")
    return data


class RejectedAttemptError(RoboFollowError):
    """The oracle did not score an attempt complete."""


class DemoFailedError(RoboFollowError):
    """No attempt of a job was scored complete within MAX_ATTEMPTS seeds."""


class UnitRecorder:
    """Records jobs into units under `work`; one per worker process (it keeps the current
    layout's simulation and renderer between jobs)."""

    def __init__(self, compiled: Benchmark, options: Options, work: Path):
        self.compiled, self.options, self.work = compiled, options, work
        self.runner = ExpertRunner(options.width, options.height)

    def __call__(self, job: DemoJob) -> dict:
        """{"job", "demo"}, or {"job", "failed"} when no attempt was complete."""
        try:
            return {"job": job.key, "demo": self.record(job)}
        except DemoFailedError as error:
            return {"job": job.key, "failed": str(error)}

    def record(self, job: DemoJob) -> dict:
        """Record the job (unless its unit already exists); returns its demo.json record."""
        final = unit_path(self.work, job)
        if (final / "demo.json").is_file():
            return read_record(final / "demo.json")
        scratch = self.work / "tmp" / f"{job.label}.{job.index:04d}.{os.getpid()}"
        discarded = []
        for attempt in range(MAX_ATTEMPTS):
            shutil.rmtree(scratch, ignore_errors=True)
            scratch.mkdir(parents=True)
            try:
                demo = self._attempt(job, attempt, scratch)
            except RoboFollowError as error:  # rejected by the oracle, or an unstable start
                discarded.append({"seed": job.seed(attempt), "reason": str(error)})
                continue
            demo["discarded"] = discarded
            (scratch / "demo.json").write_text(json.dumps(demo, sort_keys=True), encoding="utf-8")
            final.parent.mkdir(parents=True, exist_ok=True)
            shutil.rmtree(final, ignore_errors=True)  # a leftover without demo.json
            os.replace(scratch, final)
            return demo
        shutil.rmtree(scratch, ignore_errors=True)
        raise DemoFailedError(f"{job.key}: no complete demonstration in {MAX_ATTEMPTS} seeds; "
                              f"last: {discarded[-1]['reason']}")

    def _attempt(self, job: DemoJob, attempt: int, folder: Path) -> dict:
        """Run one seed into `folder`; the demo record, or RejectedAttemptError."""
        options = self.options
        with ExitStack() as stack:
            if options.format == "hdf5":
                h5 = stack.enter_context(h5py.File(folder / "episode.hdf5", "w"))
                sink: FrameSink = ArraySink(h5, options.width, options.height)
            else:
                sink = VideoSink(folder, options.width, options.height, CONTROL_HZ)
            run = self.runner.run(self.compiled, job.episode(attempt), sink)
            sink.close()
            if not run.achieved:
                raise RejectedAttemptError("the oracle scored it incomplete: "
                                           + "; ".join(run.score.failures))
            arrays = dataset_arrays(run.trajectory, self.compiled.spec.scenes[job.scene],
                                    job.layout)
            length = len(arrays["action"])
            if sink.frames != length:
                raise RuntimeError(f"{job.key}: {sink.frames} frames for {length} actions")
            demo = {"label": job.label, "scene": job.scene, "layout": job.layout,
                    "index": job.index, "seed": job.seed(attempt), "length": length,
                    "instructions": list(job.instructions), "image_stats": sink.image_stats(),
                    "spec_digest": options.spec_digest}
            if options.format == "hdf5":
                write_hdf5_arrays(h5, arrays, demo)  # the HDF5 file holds the arrays too
            else:
                np.savez(folder / "arrays.npz", **arrays)
            return demo

    def close(self) -> None:
        self.runner.close()


def write_hdf5_arrays(h5, arrays: dict[str, np.ndarray], demo: dict) -> None:
    """The non-image part of an HDF5 episode (upstream's π HDF5 names: `action`,
    `observations/qpos`; and the objects observation, `observations/environment_state`), the
    instructions and the episode's metadata as attributes."""
    h5.create_dataset("action", data=arrays["action"])
    h5.create_dataset("observations/qpos", data=arrays["state"])
    h5.create_dataset("observations/environment_state", data=arrays["environment_state"])
    h5.create_dataset("instructions", data=json.dumps(demo["instructions"]))
    for key in ("label", "scene", "layout", "seed", "spec_digest"):
        h5.attrs[key] = demo[key]
    h5.attrs["fps"] = CONTROL_HZ
    h5.attrs["robot_type"] = ROBOT_TYPE
    h5.attrs["joint_names"] = json.dumps(list(robot.JOINT_NAMES))
