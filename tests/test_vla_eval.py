"""RoboFollow under allenai's vla-evaluation-harness: episodes run by vla-eval's own
orchestration (`vla_eval.run`, the body of `vla-eval run`, in this process) against a model
server that vla-eval serves, and scored exactly as `robofollow eval` scores them."""

import json
from pathlib import Path

import anyio
import numpy as np
import pytest

import robofollow
from robofollow import release

try:
    import vla_eval
    from vla_eval.model_servers.predict import PredictModelServer
except ImportError as missing:  # a failure, not a skip: the adapter is tested in CI
    raise ImportError("these tests need vla-eval: pip install 'robofollow[vla-eval]'") from missing

from robofollow.eval.policies.reference import ExpertPolicy
from robofollow.eval.running.chance import references
from robofollow.eval.running.episode import run_episode
from robofollow.eval.running.runner import result_record
from robofollow.integrations.vla_eval import RoboFollowBenchmark, robofollow_table
from robofollow.sim.stage import Stage

CONFIG = Path(robofollow.__file__).parent / "integrations" / "vla_eval_configs" / "robofollow.yaml"
TASK = "scene2/L0/pickup_left_cube"
BUDGET = 150  # control steps per episode: enough for the expert to pick the cube up
SMALL = {"scenes": ["scene2"], "levels": ["L0"], "budget": BUDGET, "width": 64, "height": 48}


class ReplayOrHold(PredictModelServer):
    """A vla-eval model server: in a task's first round it replays `actions` in chunks of 60
    (of which the benchmark runs 50); in the others it holds still, one action per answer."""

    def __init__(self, actions: np.ndarray):
        super().__init__()
        self.actions, self.seen, self.replaying = actions, [], False

    async def on_episode_start(self, config, ctx):
        await super().on_episode_start(config, ctx)
        self.replaying = config["task"]["episode_idx"] == 0

    def predict(self, obs, ctx):
        self.seen.append(obs)
        if self.replaying:
            return {"actions": self.actions[50 * ctx.step:50 * ctx.step + 60]}
        return {"actions": obs["state"]}


class Hold:
    """Holding still, in RoboFollow's own policy interface."""
    uses = frozenset({"state"})

    def reset(self):
        pass

    def act(self, observation):
        return observation["state"]


def robofollow_record(compiled, episode, policy) -> tuple[dict, object]:
    """The episode's record as `robofollow eval` writes it (its own loop, as JSON)."""
    with Stage(64, 48) as stage:
        run = run_episode(compiled, stage, episode, policy, budget=BUDGET)
    record = {**result_record(episode, episode.instruction, run),
              **references(compiled, episode, episode.instruction)}
    return json.loads(json.dumps(record)), run


@pytest.mark.slow
def test_vla_eval_runs_robofollow_episodes_scored_as_robofollow_eval_scores_them(tmp_path):
    compiled = release.load()  # what the vla-eval benchmark reads: the current release
    first, second = (compiled.record(f"{TASK}#r{i}") for i in (1, 2))
    expert, run = robofollow_record(compiled, first, ExpertPolicy())
    held, _ = robofollow_record(compiled, second, Hold())
    assert expert["complete"] and not held["complete"]

    server = ReplayOrHold(run.trajectory.action[1:])  # the expert's executed targets
    with vla_eval.serve_background(server) as handle:
        results = vla_eval.run(
            CONFIG, server_url=handle.url, output_dir=tmp_path, docker=False,
            benchmark_overrides={"tasks": [TASK], "episodes_per_task": 2, "params": SMALL})
    [result] = results
    assert (tmp_path / "RoboFollow_aggregate.json").is_file()
    assert result["benchmark"] == "RoboFollow" and result["num_errors"] == 0
    assert (result["mean_success"], result["mean_intent_score"]) == (0.5, 0.5)
    [task] = result["tasks"]
    assert task["task"] == TASK and task["num_episodes"] == 2
    replayed, holding = sorted(task["episodes"], key=lambda e: e["episode_id"])
    assert (replayed["steps"], holding["steps"]) == (3, BUDGET)  # model queries

    for got, want in ((replayed, expert), (holding, held)):
        metrics = dict(got["metrics"])
        assert metrics.pop("success") is want["complete"]
        assert metrics.pop("seconds") >= 0 and want.pop("seconds") >= 0
        # what a model server reads, against what the reference policies read in process
        assert metrics.pop("observed") == ["images", "instruction", "state"]
        want.pop("observed")
        if got is replayed:  # the expert's own chunks are of other lengths
            assert (metrics.pop("queries"), want.pop("queries")) == (3, run.queries)
        assert metrics == want
    assert replayed["metrics"]["episode"] == f"{TASK}#r1"
    assert (replayed["metrics"]["steps"], replayed["metrics"]["error"]) == (BUDGET, None)

    seen = server.seen[0]
    assert set(seen) == {"images", "state", "task_description"}
    assert seen["task_description"] == first.instruction and seen["state"].shape == (14,)
    assert {k: v.shape for k, v in seen["images"].items()} == {
        name: (48, 64, 3) for name in ("cam_high", "cam_left_wrist", "cam_right_wrist")}
    assert len(server.seen) == 3 + BUDGET

    cell = robofollow_table(result)["cells"]["scene2"]["L0"]
    assert (cell["episodes"], cell["IS"], cell["CR"]) == (2, 50.0, 50.0)


@pytest.mark.slow
def test_an_invalid_answer_is_a_policy_failure_scored_as_it_stands():
    bench = RoboFollowBenchmark(scenes="scene2", levels="L0", budget=BUDGET, width=32, height=24)
    try:
        task = next(t for t in bench.get_tasks() if t["name"] == TASK)
        assert task["suite"] == "scene2/L0" and task["rounds"] == 10
        assert bench.get_metadata()["max_steps"] == BUDGET

        async def episode():
            await bench.start_episode({**task, "episode_idx": 1})
            await bench.apply_action({"actions": np.zeros((2, 13))})
            return await bench.is_done(), await bench.get_result()

        done, metrics = anyio.run(episode)
        assert done and metrics["success"] is False
        assert metrics["episode"] == f"{TASK}#r2" and metrics["steps"] == 0
        assert metrics["error"] == "step 0: actions must be [T, 14] with T >= 1, got shape [2, 13]"
        assert {"intent_score", "execution_score", "stages"} <= set(metrics)
        with pytest.raises(ValueError, match="has 10 rounds"):
            bench.reset({**task, "episode_idx": 10})
    finally:
        bench.cleanup()
