"""`robofollow generate` end to end: a small LeRobot v2.1 run (2 tasks x 3 episodes, two worker
processes, 320x240) validated by `dataset check`, its videos against freshly rendered frames,
its actions replayed open-loop in the env, and an interrupted (kill -9) run resumed."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from robofollow.benchmark.rounds import find_episode
from robofollow.cli import main
from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.data.check import check
from robofollow.data.generate import GenerateError, generate
from robofollow.data.jobs import demo_jobs, demo_seed
from robofollow.data.units import Options
from robofollow.oracle.score import score
from robofollow.resources import builtin_specs
from robofollow.sim.env import RoboFollowEnv
from robofollow.sim.objects import SHAPE
from robofollow.sim.video import read_frames
from tests.sim_helpers import benchmark

pytestmark = pytest.mark.slow

TASKS = ("pickup_yellow_block_1_left", "push_left_cube_to_blue_cylinder")
# Decoded H.264 (yuv420p, crf 23) against the rendered RGB frames, per frame.
PSNR_MIN_DB = 28.0
PSNR_MEAN_DB = 31.0


def _options(tasks=TASKS, per_task=3, size=(320, 240), fmt="lerobot-v2.1",
             instructions="sample") -> Options:
    return Options(fmt, per_task, tuple(tasks), size[0], size[1], instructions,
                   benchmark().spec.digest)


@pytest.fixture(scope="module")
def dataset(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("generated") / "demos"
    result = generate(benchmark(), out, _options(), workers=2, progress=False)
    assert (result.episodes, result.demonstrations, result.recorded) == (6, 6, 6)
    return out


def _episodes(root: Path) -> list[dict]:
    return [json.loads(line) for line in (root / "meta" / "episodes.jsonl").open()]


def _frames(root: Path, index: int) -> dict[str, np.ndarray]:
    table = pq.read_table(root / f"data/chunk-000/episode_{index:06d}.parquet")
    return {key: np.array(table.column(key).to_pylist(), dtype=np.float32)
            for key in ("observation.state", "observation.environment_state", "action")}


def _env(record: dict) -> RoboFollowEnv:
    """The env on the demonstration's layout and seed (its task's L0 episode, reseeded), with
    the objects observation."""
    episode = find_episode(benchmark(), f"{record['scene']}/L0/{record['label']}#r1")
    assert episode.layout == record["layout"]
    return RoboFollowEnv(episode=episode.model_copy(
        update={"seed": record["seed"], "instruction": record["tasks"][0]}), objects=True)


def test_a_small_run_validates_with_dataset_check(dataset, capsys):
    report = check(dataset)
    assert report.ok, report.errors
    assert (report.format, report.episodes) == ("lerobot-v2.1", 6)
    episodes = _episodes(dataset)
    assert [e["label"] for e in episodes] == [TASKS[0]] * 3 + [TASKS[1]] * 3
    assert [e["seed"] for e in episodes[:3]] == [demo_seed(i, 0) for i in range(3)]
    assert report.frames == sum(e["length"] for e in episodes)
    paraphrases = {t.label: t.paraphrases for t in benchmark().spec.tasks}
    assert all(e["tasks"][0] in paraphrases[e["label"]] for e in episodes)
    info = json.loads((dataset / "meta" / "info.json").read_text())
    assert info["features"]["observation.state"]["names"][6] == "left_gripper"
    assert info["features"]["observation.environment_state"]["shape"] == [SHAPE[0] * SHAPE[1]]
    stats = json.loads((dataset / "meta" / "episodes_stats.jsonl").open().readline())["stats"]
    assert len(stats["observation.environment_state"]["mean"]) == SHAPE[0] * SHAPE[1]
    assert (info["robot_type"], info["fps"], info["total_videos"]) == ("aloha_agilex", 25, 18)
    manifest = json.loads((dataset / "manifest.json").read_text())
    assert manifest["options"]["tasks"] == list(TASKS) and manifest["failed"] == []
    assert not (dataset / ".work").exists()
    assert main(["dataset", "check", str(dataset)]) == 0
    assert "6 episodes" in capsys.readouterr().out


def test_decoded_frames_match_the_rendered_images(dataset):
    record = _episodes(dataset)[4]
    actions = _frames(dataset, 4)["action"]
    env = _env(record)
    obs, _ = env.reset()
    rendered = [obs["images"]]
    for action in actions[:-1]:
        rendered.append(env.step(action)[0]["images"])
    env.close()
    for camera in ("cam_high", "cam_left_wrist", "cam_right_wrist"):
        decoded = read_frames(dataset / "videos/chunk-000" / f"observation.images.{camera}"
                              / "episode_000004.mp4")
        assert len(decoded) == len(rendered) == record["length"]
        errors = [np.mean((a.astype(float) - b[camera]) ** 2)
                  for a, b in zip(decoded, rendered, strict=True)]
        psnr = 10 * np.log10(255 ** 2 / np.maximum(errors, 1e-10))
        assert psnr.min() > PSNR_MIN_DB and psnr.mean() > PSNR_MEAN_DB, (camera, psnr.min())


@pytest.mark.parametrize("index", [0, 3])
def test_replaying_the_actions_open_loop_reproduces_the_demonstration(dataset, index):
    record = _episodes(dataset)[index]
    frames = _frames(dataset, index)
    env = _env(record)
    obs, _ = env.reset()
    states, objects = [obs["state"]], [obs["objects"]]
    for action in frames["action"]:
        obs = env.step(action)[0]
        states.append(obs["state"])
        objects.append(obs["objects"])
    trajectory = env.trajectory()
    env.close()
    np.testing.assert_array_equal(np.array(states[:-1]), frames["observation.state"])
    # the objects observation the dataset records is the one a policy reads at that frame
    np.testing.assert_array_equal(np.array(objects[:-1]).reshape(len(objects) - 1, -1),
                                  frames["observation.environment_state"])
    behaviour = Behaviour.model_validate(benchmark().training[record["label"]].model_dump())
    result = score(behaviour, trajectory, benchmark().spec.scenes[record["scene"]])
    assert result.complete and result.intent_score == 1.0 and result.execution_score == 1.0


def _tree(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*"))
            if p.is_file()}


def test_a_run_killed_mid_way_and_resumed_equals_an_uninterrupted_run(tmp_path):
    args = ["--tasks", TASKS[0], "--episodes-per-task", "3", "--image-size", "96x72",
            "--workers", "1", "--quiet"]
    whole, broken = tmp_path / "whole", tmp_path / "broken"
    assert main(["generate", str(builtin_specs()), "--out", str(whole), *args]) == 0
    process = subprocess.Popen(
        [sys.executable, "-m", "robofollow.cli", "generate", str(builtin_specs()), "--out",
         str(broken), *args], start_new_session=True, stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL)
    first = broken / ".work/units" / TASKS[0] / "0000" / "demo.json"
    deadline = time.monotonic() + 120
    while not first.exists() and time.monotonic() < deadline and process.poll() is None:
        time.sleep(0.05)
    os.killpg(process.pid, signal.SIGKILL)
    process.wait()
    assert first.exists() and not (broken / "manifest.json").exists()
    units = sorted(p.name for p in (broken / ".work/units" / TASKS[0]).iterdir())
    assert len(units) < 3, "the run finished before it was killed"
    assert main(["generate", str(builtin_specs()), "--out", str(broken), *args]) == 1
    assert main(["generate", str(builtin_specs()), "--out", str(broken), "--resume",
                 *args]) == 0
    manifest = json.loads((broken / "manifest.json").read_text())
    assert manifest["demonstrations"] == 3
    assert _tree(broken) == _tree(whole)
    assert check(broken).ok


def test_resume_refuses_other_options_and_a_folder_of_other_files(tmp_path, capsys):
    out = tmp_path / "demos"
    (out / ".work").mkdir(parents=True)
    (out / ".work" / "options.json").write_text(json.dumps(_options().to_json()))
    with pytest.raises(GenerateError, match="episodes_per_task differ"):
        generate(benchmark(), out, _options(per_task=5), resume=True,
                 progress=False)
    other = tmp_path / "other"
    other.mkdir()
    (other / "notes.txt").write_text("mine")
    assert main(["generate", str(builtin_specs()), "--out", str(other), "--resume", "--quiet",
                 "--episodes-per-task", "1", "--tasks", TASKS[0]]) == 1
    assert "no RoboFollow generation to resume" in capsys.readouterr().err
    assert (other / "notes.txt").read_text() == "mine"


def test_jobs_sample_one_paraphrase_per_episode_or_take_them_all():
    compiled = benchmark()
    sampled = demo_jobs(compiled, 50, [TASKS[0]])
    paraphrases = next(t.paraphrases for t in compiled.spec.tasks if t.label == TASKS[0])
    assert all(len(j.instructions) == 1 and j.instructions[0] in paraphrases for j in sampled)
    assert {j.instructions[0] for j in sampled} == set(paraphrases)
    assert sampled == demo_jobs(compiled, 50, [TASKS[0]])
    every = demo_jobs(compiled, 2, [TASKS[0]], "all")
    assert all(j.instructions == paraphrases for j in every)


def test_ctrl_c_stops_the_workers_with_a_message_and_resume_finishes(tmp_path):
    out = tmp_path / "demos"
    args = [str(builtin_specs()), "--out", str(out), "--tasks", TASKS[1],
            "--episodes-per-task", "4", "--image-size", "64x48", "--workers", "2", "--quiet"]
    # a shell's background job inherits SIGINT ignored: give the run the default disposition
    process = subprocess.Popen([sys.executable, "-m", "robofollow.cli", "generate", *args],
                               start_new_session=True, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True,
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    units = out / ".work/units" / TASKS[1]
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and process.poll() is None and not (
            units.is_dir() and any(units.iterdir())):
        time.sleep(0.05)
    os.killpg(process.pid, signal.SIGINT)
    _, err = process.communicate(timeout=60)
    assert process.returncode == 130
    assert "run the same command with --resume" in err and "Traceback" not in err
    assert main(["generate", *args, "--resume"]) == 0
    assert check(out).ok and check(out).episodes == 4
