"""The compiler writes goal predicates by name (compiler/planning/goals.py) and the oracle dispatches on
those names (oracle/stages.py): every name written has its evaluator, and every evaluator is
reached by some task of the benchmark."""

from __future__ import annotations

from robofollow.compiler.planning.goals import goal_graph
from robofollow.oracle.stages import AT_REST, EVALUATORS
from tests.sim_helpers import benchmark

# execution predicates checked inside their stage's intent evaluator, not looked up by name
CHECKED_BY_THEIR_STAGE = {"held_and_lifted", "pushed_closed_low", "route_footprints",
                          "finished"}


def written() -> tuple[set[str], set[str]]:
    """The intent and execution predicate names of every training and test task's goals."""
    compiled = benchmark()
    behaviours = [*compiled.training.values(), *(t.behaviour for t in compiled.splits.tasks)]
    intents, executions = set(), set()
    for behaviour in behaviours:
        for _, node in goal_graph(behaviour).nodes(data="goal"):
            intents.add(node.intent.name)
            executions.add(node.execution.name)
    return intents, executions


def test_every_intent_predicate_has_an_evaluator_and_every_evaluator_is_reached():
    intents, _ = written()
    assert intents == set(EVALUATORS)


def test_every_execution_predicate_is_checked_and_every_at_rest_check_is_reached():
    _, executions = written()
    assert executions == set(AT_REST) | CHECKED_BY_THEIR_STAGE
    assert not set(AT_REST) & CHECKED_BY_THEIR_STAGE
