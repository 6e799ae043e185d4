"""`robofollow eval`: results per episode, the summary, resuming, policy loading and the
instruction controls."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from robofollow import release
from robofollow.cli import main
from robofollow.eval.policies.loading import PolicyLoadError, load_policy
from robofollow.eval.reports.tables import table_text
from robofollow.eval.running.instructions import given_instruction
from robofollow.eval.running.run_folder import SCORES
from robofollow.eval.running.runner import (
    START_TOLERANCE_M,
    EvalOptions,
    EvalRunError,
    evaluate,
    read_results,
    select_episodes,
    start_hash,
)
from robofollow.eval.running.scores import read_scores, write_scores
from tests.sim_helpers import episode, shipped

SCENE, LEVEL = "scene1", "L0"  # 16 tasks: one round is 16 episodes


def _options(policy: str = "expert", **changes) -> EvalOptions:
    fields = {"policy": policy, "scenes": (SCENE,), "levels": (LEVEL,), "rounds": 1,
              "instruction_mode": "normal", "video": "none",
              "spec_digest": shipped().spec.digest, "release": shipped().release,
              "release_digest": shipped().release_digest}
    return EvalOptions(**{**fields, **changes})


@pytest.fixture(scope="module")
def expert_run(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("eval") / "expert"
    evaluate(shipped(), out, _options(), progress=False)
    return out


@pytest.mark.slow
def test_the_expert_run_records_every_episode_and_scores_in_full(expert_run):
    results = read_results(expert_run / "episodes.jsonl")
    assert len(results) == len({r["episode"] for r in results}) == 16
    summary = json.loads((expert_run / "summary.json").read_text())
    cell = summary["cells"][SCENE][LEVEL]
    assert {k: cell[k] for k in ("IS", "ES", "CR", "episodes", "tasks", "followed_IS")} == {
        "IS": 100.0, "ES": 100.0, "CR": 100.0, "episodes": 16, "tasks": 16, "followed_IS": 100.0}
    assert 100 / 16 <= cell["chance_CR"] <= cell["chance_IS"] < 50  # one of 16 behaviours
    assert summary["avg"] == {"IS": 100.0, "ES": 100.0, "CR": 100.0}
    assert summary["references"] == {k: cell[k] for k in ("chance_IS", "chance_CR",
                                                          "followed_IS")}
    printed = table_text(summary)
    assert f"Chance    IS {cell['chance_IS']:.1f}  CR {cell['chance_CR']:.1f}" in printed
    assert "Followed" not in printed  # shown only when it is below 100
    record = results[0]
    assert record["steps"] == 500 and record["error"] is None
    assert record["instruction"] == episode(record["episode"]).instruction
    assert "task_instruction" not in record  # only where another instruction was given
    first = record["stages"][0]
    assert first["intent"] == first["execution"] == first["weight"] and set(record["hashes"]) == {
        "episode", "split", "instruction", "initial_state", "start", "trajectory"}
    assert record["start_tolerance_m"] == START_TOLERANCE_M
    assert summary["splits"] == {SCENE: [release.manifest(shipped().release)
                                         .scenes[SCENE].split[:16]]}
    scores = read_scores(expert_run / SCORES)
    assert [row["episode"] for row in scores] == sorted(r["episode"] for r in results)
    assert all(row["intent"] == row["execution"] == 1.0 and row["complete"] for row in scores)
    assert {row["hash"] for row in scores} == {r["hashes"]["episode"] for r in results}
    assert {row["start"] for row in scores} == {r["hashes"]["start"] for r in results}
    trajectories = {row["trajectory"] for row in scores}
    assert trajectories == {r["hashes"]["trajectory"] for r in results} and len(trajectories) == 16
    again = expert_run.parent / "again.csv.gz"
    write_scores(again, list(reversed(results)))  # the same bytes in any finishing order
    assert again.read_bytes() == (expert_run / SCORES).read_bytes()


@pytest.mark.slow
def test_a_killed_run_resumes_with_every_episode_once_and_the_same_summary(expert_run,
                                                                          tmp_path):
    out = tmp_path / "broken"
    args = ["eval", "--policy", "expert", "--out", str(out),
            "--scenes", SCENE, "--levels", LEVEL, "--rounds", "1", "--workers", "2", "--quiet"]
    process = subprocess.Popen([sys.executable, "-m", "robofollow.cli", *args],
                               start_new_session=True, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL)
    results = out / "episodes.jsonl"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and process.poll() is None and (
            not results.exists() or results.read_text().count("\n") < 3):
        time.sleep(0.05)
    os.killpg(process.pid, signal.SIGKILL)
    process.wait()
    kept = read_results(results)
    assert 3 <= len(kept) < 16
    with open(results, "a") as f:  # a line the kill cut short
        f.write('{"episode": "scene1/L0/cut')
    assert main(args) == 1  # the folder holds a run: --resume is needed
    assert main(args + ["--resume"]) == 0
    again = read_results(results)
    assert sorted(r["episode"] for r in again) == sorted(
        r["episode"] for r in read_results(expert_run / "episodes.jsonl"))
    assert again[:len(kept)] == kept
    first = read_results(expert_run / "episodes.jsonl")
    assert _trajectories(again) == _trajectories(first)  # every episode reproduced exactly
    assert (out / "summary.json").read_text() == (expert_run / "summary.json").read_text()
    assert "| scene1 | 100.0 | 100.0 | 100.0 |" in (out / "report.md").read_text()


def _trajectories(records: list[dict]) -> dict[str, str]:
    return {r["episode"]: r["hashes"]["trajectory"] for r in records}


def test_a_run_folder_is_not_reused_with_other_options(tmp_path):
    out = tmp_path / "run"
    out.mkdir()
    (out / "run.json").write_text(json.dumps(_options().to_json()))
    (out / "episodes.jsonl").write_text(json.dumps(  # a run that finished an episode
        {"episode": "scene2/L0/pickup_left_cube#r1", "scene": "scene2", "level": "L0",
         "task": "scene2/L0/pickup_left_cube", "intent_score": 0.0, "execution_score": 0.0,
         "complete": False}) + "\n")
    with pytest.raises(EvalRunError, match="rounds differ"):
        evaluate(shipped(), out, _options(rounds=2), resume=True, progress=False)
    with pytest.raises(EvalRunError, match="already holds a run"):
        evaluate(shipped(), out, _options(), progress=False)
    other = tmp_path / "other"
    other.mkdir()
    (other / "mine.txt").write_text("x")
    with pytest.raises(EvalRunError, match="not empty and holds no run"):
        evaluate(shipped(), other, _options(), progress=False)


class Holder:
    uses = frozenset({"state"})

    def reset(self):
        pass

    def act(self, observation):
        return observation["state"][None]


def make_holder():
    return Holder()


class Sleeper(Holder):
    def act(self, observation):
        time.sleep(600)


def make_sleeper():
    return Sleeper()


def not_a_policy():
    return object()


def test_policies_load_by_name_or_module_factory_with_clear_errors():
    assert type(load_policy("noop")).__name__ == "NoopPolicy"
    assert isinstance(load_policy("tests.test_eval_runner:make_holder"), Holder)
    for spec, message in (("tests.test_eval_runner:missing", "has no callable 'missing'"),
                          ("no_such_module_xyz:f", "cannot import no_such_module_xyz"),
                          ("tests.test_eval_runner:not_a_policy", "is not a policy"),
                          ("gpt", "expected one of expert, blind, noop, random, "
                                  "baseline:NAME, a checkpoint folder, module:factory")):
        with pytest.raises(PolicyLoadError, match=message):
            load_policy(spec)


def test_the_instruction_controls():
    record = episode("scene2/L0/pickup_left_cube#r1")
    compiled = shipped()
    assert given_instruction(compiled, record, "normal") == record.instruction
    assert given_instruction(compiled, record, "empty") == ""
    shuffled = given_instruction(compiled, record, "shuffled")
    assert shuffled == given_instruction(compiled, record, "shuffled")  # seeded
    paraphrases = {p for t in compiled.spec.scenes["scene2"].tasks for p in t.paraphrases}
    own = next(t for t in compiled.spec.tasks if t.label == "pickup_left_cube").paraphrases
    assert shuffled in paraphrases and shuffled not in own


def test_eval_rejects_unknown_scenes_and_levels(capsys, tmp_path):
    assert main(["eval", "--policy", "noop", "--out", str(tmp_path / "r"), "--levels", "L9"]) == 2
    assert "unknown level L9; known: L0, L1, L2, L3" in capsys.readouterr().err


@pytest.mark.slow
def test_eval_can_be_limited_to_named_tasks(tmp_path, capsys):
    out = tmp_path / "two"
    args = ["eval", "--policy", "noop", "--out", str(out),
            "--rounds", "1", "--workers", "1", "--quiet", "--tasks",
            "scene2/L0/pickup_left_cube,scene4/L1/s41_l_pick_red_not_in_bowl@scene4_4"]
    assert main(args) == 0
    assert sorted(r["task"] for r in read_results(out / "episodes.jsonl")) == [
        "scene2/L0/pickup_left_cube", "scene4/L1/s41_l_pick_red_not_in_bowl@scene4_4"]
    assert main(["eval", "--policy", "noop", "--out", str(tmp_path / "x"),
                 "--tasks", "scene2/L0/pickup_left_cub"]) == 2
    error = capsys.readouterr().err
    assert "unknown task scene2/L0/pickup_left_cub;" in error
    assert "did you mean scene2/L0/pickup_left_cube" in error


@pytest.mark.slow
@pytest.mark.parametrize("mode", ["shuffled", "empty"])
def test_a_run_given_other_instructions_records_the_tasks_own(tmp_path, mode):
    out = tmp_path / mode
    assert main(["eval", "--policy", "noop", "--out", str(out),
                 "--rounds", "1", "--workers", "1", "--quiet", "--instruction-mode", mode,
                 "--tasks", "scene2/L0/pickup_left_cube"]) == 0
    [record] = read_results(out / "episodes.jsonl")
    own = episode(record["episode"]).instruction
    assert record["task_instruction"] == own and record["instruction"] != own
    assert "L0 · " + own[:20] in (out / "report.md").read_text()  # the task named by it


def test_a_sample_keeps_n_tasks_of_every_scene_and_level_spread_over_its_list():
    every = select_episodes(shipped(), _options(scenes=("scene1", "scene4"),
                                                  levels=("L0", "L1")))
    sampled = select_episodes(shipped(), _options(scenes=("scene1", "scene4"),
                                                    levels=("L0", "L1"), sample=3))
    for scene in ("scene1", "scene4"):
        for level in ("L0", "L1"):
            tasks = list(dict.fromkeys(e.task for e in every
                                       if (e.scene, e.level) == (scene, level)))
            kept = [e.task for e in sampled if (e.scene, e.level) == (scene, level)]
            assert kept == [tasks[0], tasks[len(tasks) // 3], tasks[2 * len(tasks) // 3]]
    assert len(select_episodes(shipped(), _options(sample=100))) == 16  # fewer tasks: all


def test_a_hung_in_process_policy_is_cut_at_its_time_limit_in_the_worker_pool(tmp_path,
                                                                               capsys):
    out = tmp_path / "hung"
    two = "scene2/L0/pickup_left_cube,scene1/L0/pickup_yellow_block_2"
    args = ["eval", "--policy", "tests.test_eval_runner:make_sleeper", "--out", str(out),
            "--rounds", "1", "--workers", "2", "--quiet", "--tasks", two, "--policy-timeout", "1"]
    assert main(args) == 3  # finished, with policy failures
    assert "2 of 2 episodes ended in a policy failure" in capsys.readouterr().out
    results = read_results(out / "episodes.jsonl")
    assert [(r["error"], r["steps"]) for r in results] == [
        ("step 0: the policy did not answer within 1 s", 0)] * 2
    assert json.loads((out / "run.json").read_text())["policy_timeout"] == 1.0
    assert main(["eval", "--policy", "ws://localhost:8000", "--out", str(tmp_path / "ws"),
                 "--policy-timeout", "5"]) == 2
    assert "a server takes its own: --policy URL?timeout=S&retries=N" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(args[:-1] + ["0"])
    assert "must be a positive number of seconds, got 0" in capsys.readouterr().err


def test_the_start_hash_reads_the_start_within_its_tolerance():
    positions = np.array([[0.1, 0.2, 0.3], [0.4, -0.5, 0.6]])
    quaternions = np.array([[1.0, 0.0, 0.0, 0.0], [0.7071, 0.0, 0.0, 0.7071]])
    start = start_hash(positions, quaternions)
    assert start_hash(positions + START_TOLERANCE_M / 100, quaternions) == start
    assert start_hash(positions, -quaternions) == start  # one rotation, either sign
    moved = positions.copy()
    moved[1, 0] += 2 * START_TOLERANCE_M
    assert start_hash(moved, quaternions) != start
