"""What a cache hands out is shared by every later caller in the process, so it cannot be
changed in place: the compiled benchmark and the goal nodes the oracle scores with."""

from __future__ import annotations

import dataclasses
import pickle

import pytest

from robofollow.compiler.planning.goals import scoring_nodes
from robofollow.compiler.planning.profile import DEFAULT_PROFILE
from tests.sim_helpers import benchmark


def test_the_compiled_benchmark_cannot_be_changed_in_place():
    compiled = benchmark()
    with pytest.raises(dataclasses.FrozenInstanceError):
        compiled.spec = None
    with pytest.raises(TypeError):
        compiled.training["another"] = next(iter(compiled.training.values()))
    report = compiled.report
    report["counts"].clear()
    assert compiled.report["counts"] and compiled.report != report


def test_a_compiled_benchmark_pickles_for_worker_processes_and_stays_read_only():
    compiled = benchmark()
    copy = pickle.loads(pickle.dumps(compiled))
    assert dict(copy.training) == dict(compiled.training) and copy.report == compiled.report
    with pytest.raises(TypeError):
        copy.training["another"] = None


def test_the_cached_goal_nodes_are_read_only():
    behaviour = next(iter(benchmark().training.values()))
    node, _ = scoring_nodes(behaviour, DEFAULT_PROFILE)[0]
    with pytest.raises(dataclasses.FrozenInstanceError):
        node.weight = 1.0
    with pytest.raises(TypeError):
        node.intent.params["arm"] = "right"
    assert scoring_nodes(behaviour, DEFAULT_PROFILE)[0][0] is node
