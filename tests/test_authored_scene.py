"""A scene family written from docs/spec-language.md alone (tests/data/authored_scene/scene6.rf,
stacking towers) compiles clean beside the shipped specs, leaves their splits as
specs/splits.lock pins them, has tasks at every level, and its first L0 episode is one the
scripted expert completes in simulation."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from robofollow.benchmark.compiled import clean
from robofollow.benchmark.pipeline import compile_specs
from robofollow.benchmark.rounds import episodes
from robofollow.benchmark.splits_lock import LOCK_FILE, lock_entries
from robofollow.compiler.scene.spec import LEVELS
from robofollow.resources import builtin_specs
from robofollow.sim.rollout import run_expert

AUTHORED = Path(__file__).parent / "data" / "authored_scene" / "scene6.rf"


@pytest.fixture(scope="module")
def beside_the_shipped(tmp_path_factory):
    folder = tmp_path_factory.mktemp("authored") / "specs"
    shutil.copytree(builtin_specs(), folder)
    shutil.copy(AUTHORED, folder / AUTHORED.name)
    return compile_specs(folder)


def test_the_authored_scene_leaves_the_shipped_splits_as_locked(beside_the_shipped):
    assert clean(beside_the_shipped)
    locked = json.loads((builtin_specs() / LOCK_FILE).read_text())["scenes"]
    entries = lock_entries(beside_the_shipped)
    assert set(entries) == set(locked) | {"scene6"}
    assert {scene: entries[scene] for scene in locked} == locked


def test_the_authored_scene_has_tasks_at_every_level(beside_the_shipped):
    counts = {level: len(beside_the_shipped.splits.of("scene6", level)) for level in LEVELS}
    assert all(counts.values()), counts


def test_the_expert_completes_the_authored_scenes_first_episode(beside_the_shipped):
    task = beside_the_shipped.splits.of("scene6", "L0")[0]
    episode = episodes(beside_the_shipped, task)[0]
    result = run_expert(beside_the_shipped, episode)
    assert result.achieved, (episode.id, result.score.failures)
    assert result.score.intent_score == result.score.execution_score == 1.0
