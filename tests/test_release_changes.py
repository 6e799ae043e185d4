"""What a change to the specs or the generator does to releases and runs: an episode's hash
covers only what decides it, so an added layout changes no other episode's hash; `release diff`
counts what changed per cell; runs of two releases pair only on the episodes that are the same
in both; and the shipped runs still reproduce from their release whatever the working compile
has become (a changed cap order, an added Scene 1 layout)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from robofollow import compiled_cache, release
from robofollow.benchmark.pipeline import compile_specs
from robofollow.cli import main
from robofollow.compiler.splits import generator
from robofollow.eval.reports.comparison import compare_runs
from robofollow.eval.reports.release_diff import release_diff
from robofollow.eval.running.runner import EvalOptions
from robofollow.resources import builtin_specs
from tests.sim_helpers import SHIPPED_RELEASE, shipped

pytestmark = pytest.mark.slow

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results"
ADDED = "scene1_added"  # the layout the tests add to Scene 1
LAYOUT = f"    layout {ADDED} from default {{ swap red_sphere red_cylinder }}\n"


def _specs(tmp_path: Path, change) -> Path:
    """A copy of the built-in specs with scene1.rf changed by `change` (text -> text)."""
    specs = tmp_path / "specs"
    shutil.copytree(builtin_specs(), specs)
    scene1 = specs / "scene1.rf"
    scene1.write_text(change(scene1.read_text()))
    return specs


def _added_layout(text: str) -> str:
    """Scene 1 with a fourth layout, listed in its L1 and L3 rules."""
    text = text.replace("    split L0 rounds=10", LAYOUT + "\n    split L0 rounds=10", 1)
    return text.replace("layouts=(scene1_1,", f"layouts=({ADDED}, scene1_1,")


def _moved_jitter(text: str) -> str:
    """Scene 1 with the red ball's jitter narrowed: every Scene 1 episode starts otherwise."""
    return text.replace("jitter red_sphere     x=[-0.015, 0.015]",
                        "jitter red_sphere     x=[-0.014, 0.014]", 1)


@pytest.fixture(scope="module")
def added_layout(tmp_path_factory):
    """The working compile of the built-in specs frozen as va, and with a Scene 1 layout
    added as vb (whatever the generator is now: neither is a shipped release)."""
    root = tmp_path_factory.mktemp("added")
    before, after = compile_specs(builtin_specs()), compile_specs(_specs(root, _added_layout))
    releases = root / "releases"
    release.freeze(before, "v100", releases)
    release.freeze(after, "v101", releases)
    return before, after, releases


def test_an_added_layout_changes_no_other_episodes_hash(added_layout):
    compiled, changed, _ = added_layout
    working = compiled_cache.of(changed)
    before = release.content_hashes(compiled_cache.of(compiled))
    after = {e: json.loads(line)["hash"] for e, line in zip(working.ids, working.lines,
                                                             strict=True)}
    assert after == release.content_hashes(working)  # a build's records carry this hash
    assert any(e.startswith("scene1/L1/") and e.endswith(f"@{ADDED}#r1") for e in after)
    for prefix in ("scene1/L0/", "scene2/", "scene3/", "scene4/"):
        kept = [e for e in before if e.startswith(prefix)]
        assert kept and all(after.get(e) == before[e] for e in kept), prefix


def test_release_diff_counts_what_an_added_layout_changed(added_layout, monkeypatch):
    _, _, releases = added_layout
    rows = {(r["scene"], r["level"]): r for r in release.diff(
        release.load("v100", releases), release.load("v101", releases))}
    l0 = rows["scene1", "L0"]
    assert l0["episodes"] == {"added": 0, "removed": 0, "changed": 0,
                              "unchanged": l0["episodes"]["unchanged"]} and l0["same"]
    assert rows["scene1", "L1"]["tasks"]["added"] >= 1
    assert rows["scene1", "L1"]["episodes"]["changed"] == 0
    for scene in ("scene2", "scene3", "scene4"):
        for level in ("L0", "L1", "L2", "L3"):
            counts = rows[scene, level]["episodes"]
            assert counts["unchanged"] > 0 and counts["added"] == counts["removed"] == \
                counts["changed"] == 0, (scene, level)
    monkeypatch.setattr(release, "releases_dir", lambda: releases)
    tasks, episodes = l0["tasks"]["unchanged"], l0["episodes"]["unchanged"]
    assert (f"| scene1 L0 | 0 | 0 | 0 | {tasks} | 0 | 0 | 0 | {episodes} |"
            in release_diff("v100", "v101"))


def _run(folder: Path, benchmark, episodes: list[str], intent: float) -> Path:
    """A run folder holding `episodes` of `benchmark`, each scored `intent`."""
    folder.mkdir(parents=True)
    options = EvalOptions("noop", ("scene1", "scene2"), ("L0",), 1, "normal", "none",
                          benchmark.spec.digest, release=benchmark.release,
                          release_digest=benchmark.release_digest)
    (folder / "run.json").write_text(json.dumps(options.to_json()))
    records = []
    for episode_id in episodes:
        episode = benchmark.record(episode_id)
        records.append({"episode": episode.id, "scene": episode.scene, "level": episode.level,
                        "task": episode.task, "layout": episode.layout, "seed": episode.seed,
                        "intent_score": intent, "execution_score": intent,
                        "complete": intent == 1.0,
                        "hashes": {"episode": episode.hash, "split": episode.split}})
    (folder / "episodes.jsonl").write_text("".join(json.dumps(r) + "\n" for r in records))
    return folder


def test_runs_of_two_releases_pair_only_the_episodes_that_are_the_same(tmp_path, monkeypatch):
    """Scene 1's jitter changed in v2: its episodes keep their ids but start otherwise, so a
    comparison of a v1 run with a v2 run pairs only Scene 2's, and says so."""
    specs = _specs(tmp_path, _moved_jitter)
    releases = tmp_path / "releases"
    shutil.copytree(release.releases_dir() / SHIPPED_RELEASE, releases / SHIPPED_RELEASE)
    release.freeze(compile_specs([specs / "scene1.rf", specs / "scene2.rf"]), "v2", releases)
    monkeypatch.setattr(release, "releases_dir", lambda: releases)
    old, new = release.load(SHIPPED_RELEASE), release.load("v2")
    chosen = [e for e in old.ids if e.endswith("#r1") and e.split("/")[1] == "L0"
              and e.split("/")[0] in ("scene1", "scene2")]
    assert set(chosen) <= set(new.index)
    a = _run(tmp_path / "a", old, chosen, 1.0)
    b = _run(tmp_path / "b", new, chosen, 0.0)
    found = compare_runs(a, b)
    scene1 = sum(e.startswith("scene1/") for e in chosen)
    assert found["pairing"]["pairs"] == len(chosen) - scene1 > 0
    assert found["pairing"]["other_episode"] == scene1 > 0
    assert any("different test sets" in w and "release v2" in w for w in found["warnings"])
    assert {row["scene"] for row in found["rows"]} <= {"scene2", "all"}
    rows = {(r["scene"], r["level"]): r for r in release.diff(old, new)}
    assert rows["scene1", "L0"]["episodes"]["changed"] == 160
    assert rows["scene2", "L0"]["episodes"]["unchanged"] == 160


@pytest.mark.parametrize("change", ["cap order", "added layout"])
def test_the_shipped_runs_reproduce_from_their_release_whatever_the_working_compile(
        tmp_path, monkeypatch, capsys, change):
    """A generator change with the specs unchanged (another cap order), or an added Scene 1
    layout, gives another working compile; the shipped expert run still reproduces, from v1,
    run from a folder whose ./specs is the changed one."""
    if change == "cap order":
        monkeypatch.setattr(generator, "_digest_of", lambda task_id: task_id[::-1])
        specs = builtin_specs()
    else:
        specs = _specs(tmp_path, _added_layout)
    working = compiled_cache.of(compile_specs([*sorted(specs.glob("*.rf"))]))
    assert set(working.ids) != set(shipped().ids)
    monkeypatch.chdir(specs.parent if change == "added layout" else tmp_path)
    moved = [e for e in shipped().ids if e not in working.index][:1]
    episodes = [*moved, "scene1/L0/pickup_yellow_block_1_left#r1"]
    argv = ["reproduce", str(RESULTS / "expert")]
    for episode in episodes:
        argv += ["--episode", episode]
    assert main(argv) == 0
    captured = capsys.readouterr()
    assert "reproduced" in captured.out and "benchmark: release v1" in captured.err
