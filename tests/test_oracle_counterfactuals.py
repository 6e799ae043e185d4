"""A meta-evaluation of the scorer: the expert, and policies derived from it that get one thing
wrong, recorded in MuJoCo and scored. Each counterfactual asserts exactly what it must lose."""

from __future__ import annotations

import numpy as np
import pytest

from robofollow.compiler.planning.plans import Plan, plan
from robofollow.compiler.scene.behaviour import Behaviour, Step
from robofollow.oracle.score import score
from robofollow.sim import robot
from robofollow.sim.expert import Expert
from robofollow.sim.rollout import Rollout
from robofollow.sim.stage import Stage
from tests.judged import Script
from tests.sim_helpers import benchmark, episode


def behaviour_of(record: dict) -> Behaviour:
    return record.behaviour


def perform(record: dict, behaviour: Behaviour | None = None, edit=None, extra: int = 0):
    """Record the expert of `behaviour` (default: the episode's) in the episode's layout and
    seed, its plan changed by `edit`; then score the recording against the episode."""
    rollout = Rollout(benchmark(), Stage(64, 48), record, render=False)
    points = plan(behaviour or behaviour_of(record), rollout.world)
    actions = Expert(rollout.sim).actions(edit(points) if edit else points)
    rollout.execute(list(actions) + [actions[-1]] * extra)
    return rollout.finish()[0]


def credits(result) -> list[tuple[float, float]]:
    return [(s.intent, s.execution) for s in result.stages]


def full(result) -> list[tuple[float, float]]:
    return [(s.weight, s.weight) for s in result.stages]


def with_steps(behaviour: Behaviour, **update) -> Behaviour:
    steps = tuple(s.model_copy(update=update) for s in behaviour.steps)
    return behaviour.model_copy(update={"steps": steps})


# (a) another task's behaviour in the same layout: Intent 0 from the first stage that differs
@pytest.mark.parametrize("asked, done, differs", [
    ("scene1/L0/place_yellow_block_1_behind_red_cylinder#r1",
     "place_yellow_block_1_beside_red_cylinder", 1),  # same object, another relation
    ("scene2/L0/pickup_left_cube#r1", "pickup_right_cube", 0),  # another object
    ("scene2/L0/stack_left_cube_on_red_cylinder#r2", "push_left_cube_to_red_cylinder", 0),
    ("scene3/L0/r_pick2_via4_to6_short_front#r1", "r_pick2_via5_to6_short_front", 1),
])
def test_another_tasks_behaviour_loses_intent_from_the_first_differing_stage(asked, done,
                                                                              differs):
    record = episode(asked)
    result = perform(record, benchmark().training[done])
    got = credits(result)
    assert got[:differs] == full(result)[:differs]
    assert all(intent == 0.0 for intent, _ in got[differs:]), result.stages
    assert not result.complete
    assert result.executed_behaviour.match == done
    assert result.executed_behaviour.intent_score == 1.0


# (b) the right object, dropped on the way
def _drop_after_lift(points: Plan) -> Plan:
    """Open the gripper where the object was lifted, then go on as planned, empty-handed."""
    lift = [p.name for p in points.points].index("lift")
    opened = [p.model_copy(update={"gripper": 1.0}) for p in points.points[lift:]]
    drop = opened[0].model_copy(update={"name": "drop"})
    return Plan(points=points.points[:lift + 1] + (drop, *opened[1:]))


@pytest.mark.parametrize("asked", ["scene1/L0/place_yellow_block_2_left_of_red_sphere#r1",
                                   "scene2/L0/place_right_cube_in_green_bowl#r1",
                                   "scene3/L0/l_pick5_around2_to1_short_right#r1"])
def test_dropped_mid_transport_keeps_the_grasp_and_loses_the_objective(asked):
    result = perform(episode(asked), edit=_drop_after_lift)
    source, objective = result.stages[0], result.stages[1]
    assert (source.intent, source.execution) == (source.weight, source.weight)
    assert objective.execution == 0.0 and not result.complete


# (c) succeeds, then does not come home, or comes home and moves on
def _stay_put(points: Plan) -> Plan:
    return Plan(points=tuple(p for p in points.points if p.name != "home"))


def _move_on(points: Plan) -> Plan:
    retreat = next(p for p in points.points if p.name in ("retreat", "lift"))
    later = retreat.model_copy(update={"name": "again"})
    return Plan(points=points.points + (later,))


@pytest.mark.parametrize("asked", ["scene1/L0/place_yellow_block_1_behind_red_sphere#r1",
                                   "scene2/L0/push_left_cube_to_red_cylinder#r1",
                                   "scene4/L0/s41_r_stack_green_cylinder_on_yellow#r1"])
@pytest.mark.parametrize("edit", [_stay_put, _move_on])
def test_not_finishing_loses_exactly_the_finishing_stage(asked, edit):
    result = perform(episode(asked), edit=edit, extra=30)
    assert credits(result)[:-1] == full(result)[:-1]
    assert result.stages[-1].name == "finish" and credits(result)[-1] == (0.0, 0.0)
    assert result.intent_score == result.execution_score == pytest.approx(0.8)
    assert result.complete  # completion does not ask for the finish


# (d) the wrong arm: the named arm is part of the instruction
def test_the_wrong_arm_earns_nothing_and_is_recognised():
    record = episode("scene1/L0/pickup_yellow_block_1_left#r1")
    result = perform(record, with_steps(behaviour_of(record), arm="right"))
    assert result.intent_score == result.execution_score == 0.0 and not result.complete
    assert "the right arm, not the left, grasped yellow_block_1" in result.stages[0].reason
    assert result.executed_behaviour.match == "pickup_yellow_block_1_right"


def test_the_other_arm_grasping_as_well_loses_the_finish():
    """Both arms pick: the named one first, so only the finish (idle arm) is lost."""
    record = episode("scene4/L0/s41_l_pick_blue_sphere#r1")
    both = Behaviour(steps=behaviour_of(record).steps + (
        Step(action="pick", arm="right", source="green_cylinder"),))
    result = perform(record, both)
    assert credits(result)[0] == full(result)[0]
    assert credits(result)[1] == (0.0, 0.0)
    assert "idle right arm grasped green_cylinder" in result.stages[1].reason
    assert result.complete  # the paper's rule for pickups: IS and ES at least 0.8


# (e) doing nothing scores nothing
@pytest.mark.parametrize("asked", [
    "scene1/L0/pickup_yellow_block_2#r1", "scene2/L0/push_left_cube_to_red_cylinder#r1",
    "scene3/L0/r_pick2_via4_to6_long_front#r1", "scene4/L0/s41_seq_l_bowl_then_r_green_cylinder#r1",
    "scene4/L0/s41_if_bowl_nonempty_then_l_pick_blue_else_r_stack#r1"])
def test_a_no_op_scores_zero_everywhere(asked):
    record = episode(asked)
    rollout = Rollout(benchmark(), Stage(64, 48), record, render=False)
    rollout.execute([robot.home_state()] * 150)
    result = rollout.finish()[0]
    assert all(c == (0.0, 0.0) for c in credits(result)) and not result.complete
    assert result.executed_behaviour.description == "nothing moved"
    assert result.executed_behaviour.match is None and result.executed_behaviour.arms_moved is False


# (f) a conditional, the branch its condition does not select
def test_the_wrong_branch_of_a_conditional_earns_no_intent():
    record = episode("scene4/L0/s41_if_bowl_nonempty_then_l_pick_blue_else_r_stack#r1")
    asked = behaviour_of(record)
    result = perform(record, Behaviour(steps=asked.other))
    assert result.intent_score == 0.0 and result.other_branch is True
    assert result.executed_behaviour.match == "other branch"
    assert perform(record).other_branch is False


# (g) a sequence in reverse order
def test_a_sequence_in_reverse_order_scores_zero():
    record = episode("scene4/L0/s41_seq_l_bowl_then_r_green_cylinder#r1")
    asked = behaviour_of(record)
    result = perform(record, asked.model_copy(update={"steps": asked.steps[::-1]}))
    assert result.intent_score == result.execution_score == 0.0
    assert all(s.reason.startswith("out of order") for s in result.stages)
    assert result.executed_behaviour.match == "s41_seq_r_green_cylinder_then_l_bowl"


# (h) the route over the slab it was told to avoid
def test_a_route_over_the_forbidden_slab_loses_the_route_stage():
    record = episode("scene3/L0/l_pick5_around2_to1_short_right#r1")
    asked = behaviour_of(record)
    (_, avoided), = asked.steps[0].waypoints
    result = perform(record, with_steps(asked, waypoints=(("via", avoided),)))
    source, route, outcome, _ = result.stages
    assert (source.intent, source.execution) == (0.24, 0.24)
    assert (route.intent, route.execution) == (0.0, 0.0)
    assert outcome.intent == outcome.execution == 0.0 and not result.complete


# (i) the right route, the wrong final orientation
@pytest.mark.parametrize("asked", ["scene3/L0/r_pick2_via4_to6_short_front#r1",
                                   "scene3/L0/l_pick5_around2_to1_short_right#r1"])
def test_a_wrong_final_orientation_loses_only_the_orientation_stage(asked):
    record = episode(asked)
    behaviour = behaviour_of(record)
    turned = (behaviour.steps[0].yaw_degrees + 90.0) % 180.0
    result = perform(record, with_steps(behaviour, yaw_degrees=turned))
    assert credits(result)[:2] == full(result)[:2]
    reason = result.stages[2].reason
    label = behaviour.steps[0].target
    assert credits(result)[2] == (0.0, 0.0)
    assert f"released on {label}, but turned 90 deg off the asked yaw" in reason, reason
    assert result.intent_score == result.execution_score == pytest.approx(0.48)
    assert not result.complete


def test_expert_scores_are_deterministic():
    record = episode("scene2/L0/stack_left_cube_on_red_cylinder#r1")
    a, b = perform(record), perform(record)
    assert a == b and credits(a) == full(a)
    assert np.isclose(a.intent_score, 1.0)


# (j) a sequence mixing a pickup and a placement: each step's end state decides completion
def test_a_mixed_sequence_completes_on_every_steps_end_state():
    record = episode("scene1/L0/place_yellow_block_1_behind_red_cylinder#r1")
    both = Behaviour(steps=(Step(action="pick", arm="left", source="yellow_block_2"),
                            behaviour_of(record).steps[0]))
    scene = benchmark().spec.scenes["scene1"]
    done = Script(record.id).perform(both)
    result = score(both, done.trajectory(), scene)
    assert result.intent_score == result.execution_score == 1.0 and result.complete
    dropped = Script(record.id).perform(both).grip("left", 1.0)  # lets the pickup go
    result = score(both, dropped.trajectory(), scene)
    assert result.stages[-1].intent == 0.0 and not result.complete


def test_arms_that_move_in_free_air_touched_nothing_and_are_told_from_still_ones():
    """A waving arm that touches nothing earns nothing, like a no-op, but the record says its
    arms moved (the reports count it apart from 'nothing moved')."""
    record = episode("scene2/L0/pickup_left_cube#r1")
    rollout = Rollout(benchmark(), Stage(64, 48), record, render=False)
    waved = robot.home_state()
    waved[0] += 0.25  # the left arm's waist turns, at home height
    rollout.execute([waved] * 60 + [robot.home_state()] * 90)
    result = rollout.finish()[0]
    assert all(c == (0.0, 0.0) for c in credits(result)) and not result.complete
    assert result.executed_behaviour.description == "the arms moved but touched nothing"
    assert result.executed_behaviour.arms_moved is True and result.executed_behaviour.match is None
