"""The five full-benchmark baselines ship with the package and reproduce their recorded runs:
for each, 8 round-1 episodes of different scenes and levels, run again by name
(`eval --policy baseline:NAME --tasks ... --rounds 1`), give the trajectory hashes recorded in
docs/results/baselines/NAME/scores.csv.gz (the same NumPy build and CPU family: inference runs
through NumPy's matrix products). So do the two objects kinds' second-seed checkpoints, shipped
with their runs in docs/results/baselines/KIND-seed1/checkpoint."""

from __future__ import annotations

from pathlib import Path

import pytest

from robofollow.cli import main
from robofollow.compiler.spec import LEVELS
from robofollow.eval.saved_run import load_records

pytestmark = pytest.mark.slow

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results" / "baselines"
FULL = ("text", "blind", "form", "objects-text", "objects-form")
SECOND_SEED = ("objects-text-seed1", "objects-form-seed1")
SCENES = ("scene1", "scene2", "scene3", "scene4")
SAMPLED = 8


def sampled(records: list[dict], offset: int) -> list[dict]:
    """Round-1 episodes of 8 (scene, level) cells: each scene at two levels two apart,
    rotated by `offset` so that the baselines between them cover every cell; in each cell the
    middle task of the recorded list."""
    first = sorted((r for r in records if r["episode"].endswith("#r1")),
                   key=lambda r: r["episode"])
    chosen = []
    for s, scene in enumerate(SCENES):
        for level in (LEVELS[(s + offset) % 4], LEVELS[(s + offset + 2) % 4]):
            cell = [r for r in first if r["scene"] == scene and r["level"] == level]
            assert cell, f"no round-1 episode of {scene} {level} recorded"
            chosen.append(cell[len(cell) // 2])
    return chosen


def reproduces(policy: str, recorded: list[dict], run: Path, capsys) -> None:
    """Run the recorded episodes' tasks again (round 1) and compare trajectory hashes."""
    assert len(recorded) == SAMPLED and all(r["hashes"]["trajectory"] for r in recorded)
    tasks = ",".join(r["task"] for r in recorded)
    assert main(["eval", "--policy", policy, "--tasks", tasks, "--rounds", "1",
                 "--workers", "1", "--quiet", "--out", str(run)]) == 0
    capsys.readouterr()
    again = {r["episode"]: r["hashes"]["trajectory"] for r in load_records(run)}
    assert again == {r["episode"]: r["hashes"]["trajectory"] for r in recorded}


@pytest.mark.parametrize("offset,name", enumerate(FULL))
def test_a_shipped_baseline_reproduces_its_recorded_episodes(offset, name, tmp_path, capsys):
    reproduces(f"baseline:{name}", sampled(load_records(RESULTS / name), offset),
               tmp_path / name, capsys)


@pytest.mark.parametrize("offset,name", enumerate(SECOND_SEED, start=1))
def test_a_second_seed_checkpoint_reproduces_its_recorded_episodes(offset, name, tmp_path,
                                                                    capsys):
    reproduces(str(RESULTS / name / "checkpoint"), sampled(load_records(RESULTS / name), offset),
               tmp_path / name, capsys)
