"""RoboFollow as a benchmark of allenai's vla-evaluation-harness (`pip install
robofollow[vla-eval]`), named in a vla-eval config by its import path
`robofollow.integrations.vla_eval:RoboFollowBenchmark`:

    vla-eval run -c robofollow/integrations/vla_eval_configs/robofollow.yaml \\
        --server-url ws://HOST:PORT

Tasks: a vla-eval task is a RoboFollow test task (name: its id scene/level/label, suite:
scene/level); its episode `episode_idx` is the task's round episode_idx + 1 (layout and seed),
so `episodes_per_task` plays `robofollow eval --rounds`. The model server is sent
{"images": {cam_high, cam_left_wrist, cam_right_wrist} (H, W, 3) uint8, "state": float32 [14],
"task_description": the instruction} and answers {"actions": [14] or [T, 14]}: absolute joint
targets (per arm, left then right: joint_0..joint_5 and gripper, 1 open). As in `robofollow
eval`, at most 50 actions of a chunk run before the next query (images are rendered once per
query), an episode runs the fixed action budget, and an invalid answer ends it as a policy
failure. The episode is then scored by RoboFollow's oracle: its metrics are the `robofollow
eval` episode record (intent_score, execution_score, complete, stages, error, chance, ...)
with success = complete. `robofollow_table` turns a run's result into RoboFollow's Table 1.
vla-eval also sends the task dict (its name is the task id) to the server at each episode
start: with instruction_mode empty or shuffled, use servers that ignore it.
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from vla_eval.benchmarks.base import StepBenchmark, StepResult
from vla_eval.recording import NullEpisodeRecorder
from vla_eval.render import configure_mujoco_render
from vla_eval.specs import IMAGE_RGB, LANGUAGE, STATE_JOINT, DimSpec

if TYPE_CHECKING:  # (MuJoCo is imported only after configure_mujoco_render)
    from robofollow.benchmark.episode import Episode

_ALL_ROUNDS = 10 ** 9
IMAGE_POLICY_USES = frozenset({"state", "instruction", "images"})  # what a model server reads


def _names(value: str | Iterable[str] | None) -> list[str] | None:
    """A list param given as a list or a comma-separated string (None: all)."""
    if value is None:
        return None
    return [v for v in value.split(",") if v] if isinstance(value, str) else list(value)


class RoboFollowBenchmark(StepBenchmark):
    """RoboFollow's test episodes (the current release, or `release`; a working compile of
    `specs` where given), selected
    as `robofollow eval --scenes --levels --sample` does; `instruction_mode` is normal, empty
    or shuffled; `budget` is the action budget in control steps (default 500); `width` and
    `height` the camera images' size."""

    render_backends = frozenset({"gpu", "cpu"})  # MuJoCo: EGL (RoboFollow's default) or OSMesa

    @classmethod
    def configure_render(cls, mode: str) -> dict[str, str]:
        return configure_mujoco_render(mode)

    def __init__(self, specs: str | None = None, scenes: str | list[str] | None = None,
                 levels: str | list[str] | None = None, sample: int | None = None,
                 instruction_mode: str = "normal", budget: int | None = None,
                 width: int = 320, height: int = 240, release: str | None = None) -> None:
        super().__init__()
        # Imported here, after configure_render: MuJoCo binds its GL backend when imported.
        from robofollow import release as releases
        from robofollow.compiler.scene.spec import LEVELS
        from robofollow.eval.running.modes import INSTRUCTION_MODES
        from robofollow.eval.running.runner import EvalOptions, select_episodes
        from robofollow.sim import MAX_STEPS
        from robofollow.sim.stage import Stage

        if instruction_mode not in INSTRUCTION_MODES:
            raise ValueError(f"instruction_mode must be one of {INSTRUCTION_MODES}, got "
                             f"{instruction_mode!r}")
        self.budget = MAX_STEPS if budget is None else int(budget)
        if self.budget < 1:
            raise ValueError(f"budget must be at least 1 control step, got {budget}")
        self.instruction_mode = instruction_mode
        compiled = self.compiled = releases.benchmark(release, Path(specs) if specs else None)
        self.stage = Stage(width, height)  # the current layout's simulation and cameras
        scenes, levels = _names(scenes), _names(levels)
        for kind, given, known in (("scene", scenes, list(compiled.spec.scenes)),
                                   ("level", levels, list(LEVELS))):
            unknown = sorted(set(given or ()) - set(known))
            if unknown:
                raise ValueError(f"unknown {kind}s {unknown} (known: {', '.join(known)})")
        options = EvalOptions("vla-eval", tuple(scenes or compiled.spec.scenes),
                              tuple(levels or LEVELS), _ALL_ROUNDS, instruction_mode, "none",
                              compiled.spec.digest, sample=sample, release=compiled.release,
                              release_digest=compiled.release_digest)
        self._rounds: dict[str, list[Episode]] = {}
        for episode in select_episodes(compiled, options):
            self._rounds.setdefault(episode.task, []).append(episode)
        self._recorder = NullEpisodeRecorder()  # start_episode() sets the run's
        self._instruction, self._error, self._began = "", None, 0.0
        self._rollout = None  # the episode in progress (robofollow.eval.running.episode.PolicyRollout)

    # -- tasks -------------------------------------------------------------------------------

    def get_tasks(self) -> list[dict[str, Any]]:
        return [{"name": task, "suite": f"{rounds[0].scene}/{rounds[0].level}",
                 "scene": rounds[0].scene, "level": rounds[0].level,
                 "rounds": len(rounds)} for task, rounds in self._rounds.items()]

    def get_metadata(self) -> dict[str, Any]:
        rounds = [len(r) for r in self._rounds.values()]
        return {"max_steps": self.budget, "action_dim": 14,
                "max_episodes_per_task": min(rounds) if rounds else 0}

    # -- one episode ---------------------------------------------------------------------------

    def reset(self, task: dict[str, Any]) -> Any:
        """The episode's start, as robofollow.eval.running.episode.run_episode sets it up."""
        from robofollow.eval.running.episode import PolicyRollout
        from robofollow.eval.running.instructions import given_instruction

        rounds, index = self._rounds[task["name"]], int(task.get("episode_idx", 0))
        if not 0 <= index < len(rounds):
            raise ValueError(f"{task['name']} has {len(rounds)} rounds: episodes_per_task "
                             f"must be at most {len(rounds)}")
        episode = rounds[index]
        self._instruction = given_instruction(self.compiled, episode, self.instruction_mode)
        self._began, self._error = time.perf_counter(), None
        self._rollout = PolicyRollout(self.compiled, self.stage, episode, True, self.budget)
        return None

    def step(self, action: dict[str, Any]) -> StepResult:
        from robofollow.eval.policies.policy import BadActionError, validate_actions

        rollout = self._rollout
        rollout.queries += 1
        try:
            chunk, past = validate_actions(action.get("actions"))
        except BadActionError as failure:  # a policy failure: the episode is scored as it stands
            self._error = f"step {rollout.steps}: {failure}"
            return StepResult(None, 0.0, True, {})
        rollout.execute_chunk(chunk, past)
        return StepResult(None, 0.0, rollout.done, {})

    def make_obs(self, raw_obs: Any, task: dict[str, Any]) -> dict[str, Any]:
        """What `robofollow eval` shows an image policy, rendered once per query."""
        from robofollow.eval.running.episode import observation

        obs = observation(IMAGE_POLICY_USES, self.stage, self._instruction,
                          self._rollout.steps, None)
        self._recorder.record_video(obs["images"]["cam_high"])
        return {"images": obs["images"], "state": obs["state"],
                "task_description": obs["instruction"]}

    def get_step_result(self, step_result: StepResult) -> dict[str, Any]:
        """The `robofollow eval` episode record, scored by the oracle, with success."""
        from robofollow.eval.running.runner import episode_record

        run = self._rollout.result(self._error, self._began, IMAGE_POLICY_USES)
        record = episode_record(self.compiled, self._rollout.episode, self._instruction, run)
        return {"success": bool(record["complete"]), **record}

    # -- declarations --------------------------------------------------------------------------

    def get_metric_keys(self) -> dict[str, str]:
        return {"success": "mean", "intent_score": "mean", "execution_score": "mean"}

    def get_action_spec(self) -> dict[str, DimSpec]:
        return {"joints": DimSpec("joints", 14, "joint_positions", description=(
            "absolute targets, left then right arm: joint_0..joint_5, gripper (1 open)"))}

    def get_observation_spec(self) -> dict[str, DimSpec]:
        return {"cam_high": IMAGE_RGB, "cam_left_wrist": IMAGE_RGB, "cam_right_wrist": IMAGE_RGB,
                "state": STATE_JOINT, "language": LANGUAGE}

    def cleanup(self) -> None:
        self.stage.close()


def robofollow_table(result: Mapping[str, Any]) -> dict:
    """RoboFollow's Table 1 (IS / ES / CR per scene and level, robofollow.eval.statistics.metrics.table)
    over one vla-eval benchmark result (an entry of what `vla_eval.run` returns, or a
    `<name>_aggregate.json`). Episodes that vla-eval ended with an error (a lost server, a
    timeout) carry no RoboFollow scores and are left out: check the result's num_errors."""
    from robofollow.eval.statistics.metrics import table

    return table(e["metrics"] for t in result["tasks"] for e in t["episodes"]
                 if "intent_score" in e.get("metrics", {}))
