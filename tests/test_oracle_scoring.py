"""Scoring rules on edited expert recordings (edits that stay physically consistent: pauses,
the idle arm's path, the measured fingers; the judged catalogue covers simulated behaviours):
the finish stage's clauses, the profiles, the recording checks, the metrics, and
`robofollow score`."""

from __future__ import annotations

import dataclasses
import functools
import json

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from robofollow.compiler.planning.profile import (
    DEFAULT_PROFILE,
    STRICT_PROFILE,
    ScoringProfile,
)
from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.eval.statistics.metrics import table
from robofollow.oracle.score import score
from robofollow.resources import builtin_specs
from robofollow.scoring import RecordingMismatchError, score_recording
from robofollow.sim.rollout import run_expert
from robofollow.trajectory import Trajectory, TrajectoryError
from tests.cli_helpers import run
from tests.sim_helpers import benchmark, episode

PLACE = "scene1/L0/place_yellow_block_1_behind_red_cylinder#r1"  # right arm
FRAME_ARRAYS = ("time", "state", "action", "positions", "quaternions", "ee_positions",
                "ee_quaternions", "grasped", "contacts")


@pytest.fixture(scope="module")
def expert() -> Trajectory:
    record = episode(PLACE)
    return run_expert(benchmark(), record).trajectory


@functools.cache
def asked() -> Behaviour:
    return episode(PLACE).behaviour


def scored(trajectory: Trajectory, profile: ScoringProfile = DEFAULT_PROFILE):
    return score(asked(), trajectory, benchmark().spec.scenes["scene1"], profile)


def edited(trajectory: Trajectory, **arrays) -> Trajectory:
    return dataclasses.replace(trajectory, **arrays)


def held(trajectory: Trajectory, frame: int, count: int) -> Trajectory:
    """The recording with frame `frame` repeated `count` more times (a pause)."""
    index = np.concatenate([np.arange(frame + 1), np.full(count, frame),
                            np.arange(frame + 1, len(trajectory))])
    return edited(trajectory, **{k: getattr(trajectory, k)[index] for k in FRAME_ARRAYS})


def release_frame(trajectory: Trajectory) -> int:
    """The frame the right fingers stopped holding the block."""
    held = trajectory.grasped[:, 1] >= 0
    return int(np.flatnonzero(held[:-1] & ~held[1:])[0]) + 1


def test_the_expert_recording_scores_in_full(expert):
    result = scored(expert)
    assert (result.intent_score, result.execution_score, result.complete) == (1.0, 1.0, True)
    assert result.profile == DEFAULT_PROFILE.model_dump(mode="json")


def test_the_commanded_gripper_is_not_evidence(expert):
    """Commanding the gripper shut (or 0.4, or open) changes nothing the physics shows."""
    action = expert.action.copy()
    action[:, 13] = np.where(action[:, 13] < 0.5, 0.4, 1.02)
    action[3:8, 6] = 0.0
    assert scored(edited(expert, action=action)) == scored(expert)


def test_the_finish_deadline(expert):
    frame = release_frame(expert)
    late = scored(held(expert, frame + 5, 200))  # pauses 200 frames before going home
    assert late.stages[-1].intent == 0.0 and "frames after finishing" in late.stages[-1].reason
    assert late.intent_score == pytest.approx(0.8) and late.complete
    assert scored(held(expert, frame + 5, 100)).intent_score == 1.0  # within 180 frames


def test_the_idle_arm_must_keep_out_of_the_work_area(expert):
    ee = expert.ee_positions.copy()
    ee[40:45, 0] = [0.0, 0.0, 0.85]  # the left (idle) arm over the table centre
    result = scored(edited(expert, ee_positions=ee))
    assert "idle left arm entered the work area at frame 40" in result.stages[-1].reason
    assert [s.intent for s in result.stages] == [0.4, 0.4, 0.0]


@pytest.mark.parametrize("table", [0.62, 0.88])
def test_the_work_area_moves_with_the_table(expert, table):
    """The same episode on a lower or higher table (the whole recording shifted with it): the
    idle arm resting at home keeps the finish, and the idle arm 5 cm over the table's centre
    loses it, whatever the table's height."""
    scene = benchmark().spec.scenes["scene1"]
    lift = table - scene.table_height
    moved = scene.model_copy(update={"table_height": table})
    shifted = edited(expert, positions=expert.positions + [0.0, 0.0, lift],
                     ee_positions=expert.ee_positions + [0.0, 0.0, lift])
    finish = score(asked(), shifted, moved).stages[-1]
    assert finish.intent == finish.weight, finish.reason
    ee = shifted.ee_positions.copy()
    ee[40:45, 0] = [0.0, 0.0, table + 0.05]  # the left (idle) arm just over the table centre
    result = score(asked(), edited(shifted, ee_positions=ee), moved)
    assert "idle left arm entered the work area at frame 40" in result.stages[-1].reason


def test_closing_again_after_finishing_loses_the_finish(expert):
    state = expert.state.copy()
    state[-3:, 13] = 0.0  # the measured fingers shut at home, holding nothing
    result = scored(edited(expert, state=state))
    assert "closed its gripper again" in result.stages[-1].reason
    assert result.execution_score == pytest.approx(0.8) and result.complete


def test_a_profile_changes_the_thresholds_and_is_recorded(expert):
    strict = ScoringProfile(name="strict", relation_range=0.05)
    result = scored(expert, strict)
    assert result.profile["name"] == "strict" and result.profile["relation_range"] == 0.05
    objective = result.stages[1]
    assert objective.intent == 0.4 and objective.execution == 0.0  # the side is still right
    assert "(at most 5.0 cm)" in objective.reason and not result.complete


def test_the_strict_completion_profile_asks_every_stage_in_full(expert):
    late = held(expert, release_frame(expert) + 5, 200)
    assert scored(late).complete and scored(late, STRICT_PROFILE).complete  # finish not asked
    moved = expert.positions.copy()
    index = expert.index("yellow_block_1")
    moved[-12:, index, 0] += 0.2  # the block is pushed away at the very end
    paper, strict = scored(edited(expert, positions=moved)), scored(edited(expert,
                                                                         positions=moved),
                                                                  STRICT_PROFILE)
    assert not paper.complete and strict.complete  # the end state decides the paper's CR


def test_a_recording_from_another_layout_is_refused(expert):
    compiled = benchmark()
    scene4 = episode("scene4/L0/s41_l_pick_cube_in_bowl#r1")
    relabelled = dataclasses.replace(expert, meta=dict(expert.meta, layout="scene4_1"))
    with pytest.raises(RecordingMismatchError, match="bodies"):
        score_recording(compiled, scene4, relabelled)
    moved = dataclasses.replace(expert, meta=dict(expert.meta, layout="scene1_1"))
    with pytest.raises(RecordingMismatchError, match="layout 'scene1_1'"):
        score_recording(compiled, episode(PLACE), moved)


def test_a_recording_of_another_scene_cannot_be_scored(expert):
    with pytest.raises(TrajectoryError, match="unknown bodies"):
        score(asked(), expert, benchmark().spec.scenes["scene2"])
    nameless = dataclasses.replace(expert, meta={})
    with pytest.raises(TrajectoryError, match="layout None"):
        scored(nameless)


def test_bad_trajectory_files_say_what_is_wrong(tmp_path, expert):
    (tmp_path / "text.npz").write_text("not an archive")
    with pytest.raises(TrajectoryError, match="not a zip archive"):
        Trajectory.load(tmp_path / "text.npz")
    np.savez(tmp_path / "other.npz", x=np.zeros(3))
    with pytest.raises(TrajectoryError, match="missing bodies"):
        Trajectory.load(tmp_path / "other.npz")
    short = edited(expert, state=expert.state[:-1])
    short.save(tmp_path / "short.npz")
    with pytest.raises(TrajectoryError, match="state has shape"):
        Trajectory.load(tmp_path / "short.npz")


def test_metrics_follow_the_paper():
    rows = [("s1", "L0", "a", 1.0, 1.0, True), ("s1", "L0", "a", 0.4, 0.0, False),
            ("s1", "L0", "b", 0.0, 0.0, False), ("s1", "L1", "a", 1.0, 0.6, True),
            ("s2", "L0", "c", 0.8, 0.8, True)]
    results = [dict(zip(("scene", "level", "task", "intent_score", "execution_score",
                         "complete"), row, strict=True)) for row in rows]
    got = table(results)
    cell = got["cells"]["s1"]["L0"]
    assert cell["IS"] == pytest.approx(46.67) and cell["ES"] == pytest.approx(33.33)
    assert cell["CR"] == 25.0  # task a: 1/2, task b: 0/1 -> mean 25, not 1/3 of episodes
    assert cell["CR_micro"] == pytest.approx(33.33) and cell["episodes"] == 3
    assert got["avg"]["IS"] == pytest.approx((46.67 + 100 + 80) / 3, abs=0.01)
    assert got["avg"]["CR"] == pytest.approx((25 + 100 + 100) / 3, abs=0.01)


def test_the_score_command(tmp_path, expert, capsys):
    path = tmp_path / "t.npz"
    expert.save(path)
    specs = str(builtin_specs())
    status, out, _ = run(capsys, "score", str(path), "--specs", specs)
    assert status == 0 and "complete: yes" in out and "closest behaviour: instructed" in out
    other = "scene1/L0/place_yellow_block_1_beside_red_cylinder#r1"
    status, out, _ = run(capsys, "score", str(path), "--episode", other, "--json", "--specs",
                         specs)
    result = json.loads(out)
    assert status == 0 and result["intent_score"] == pytest.approx(0.4)
    assert result["executed_behaviour"]["match"] == "place_yellow_block_1_behind_red_cylinder"
    status, _, err = run(capsys, "score", str(tmp_path / "missing.npz"))
    assert status == 1 and "cannot read a trajectory" in err and "Traceback" not in err
    anonymous = dataclasses.replace(expert, meta={"layout": "default"})
    anonymous.save(tmp_path / "anonymous.npz")
    status, _, err = run(capsys, "score", str(tmp_path / "anonymous.npz"), "--specs", specs)
    assert status == 1 and "pass --episode" in err


@given(data=st.data())
def test_scores_stay_consistent_under_arbitrary_edits(expert, data):
    """Whatever the recording: credits are all-or-nothing per stage, Execution never exceeds
    Intent, gating holds, and scoring is deterministic."""
    frames, bodies = len(expert), len(expert.bodies)
    start = data.draw(st.integers(0, frames - 1))
    stop = data.draw(st.integers(start + 1, frames))
    state, positions, ee = expert.state.copy(), expert.positions.copy(), expert.ee_positions.copy()
    grasped = expert.grasped.copy()
    state[start:stop, data.draw(st.sampled_from([6, 13]))] = data.draw(st.floats(0.0, 1.0))
    grasped[start:stop, data.draw(st.integers(0, 1))] = data.draw(st.integers(-1, bodies - 1))
    shift = data.draw(st.lists(st.floats(-0.05, 0.05), min_size=3, max_size=3))
    positions[start:, data.draw(st.integers(0, bodies - 1))] += shift
    ee[start:stop, data.draw(st.integers(0, 1))] += shift
    trajectory = edited(expert, state=state, positions=positions, ee_positions=ee,
                        grasped=grasped)
    result = scored(trajectory)
    assert result == scored(trajectory)
    assert 0.0 <= result.execution_score <= result.intent_score <= 1.0
    for stage in result.stages:
        assert stage.intent in (0.0, stage.weight) and stage.execution in (0.0, stage.intent)
    intents = [s.intent > 0 for s in result.stages]
    assert intents == sorted(intents, reverse=True)  # no credit after a missed stage
    assert scored(trajectory, STRICT_PROFILE).complete == all(
        s.execution == s.weight for s in result.stages if s.name != "finish")
