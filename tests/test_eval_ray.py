"""`robofollow eval --executor ray`: the same episodes, records and summary as the process
pool."""

from __future__ import annotations

import sys

import pytest

from robofollow.cli import main
from robofollow.errors import RoboFollowError
from robofollow.eval.running.run_folder import read_results
from robofollow.resources import builtin_specs
from robofollow.workers import results

TASKS = ",".join(f"scene2/L0/{label}" for label in (
    "pickup_left_cube", "stack_left_cube_on_red_cylinder", "push_red_cylinder_to_left_cube",
    "place_right_cube_in_green_bowl"))


def _run(out, executor: str) -> tuple[list[dict], str]:
    assert main(["eval", "--policy", "blind", "--out", str(out), "--specs", str(builtin_specs()),
                 "--tasks", TASKS, "--rounds", "2", "--workers", "2", "--executor", executor,
                 "--quiet"]) == 0
    records = sorted(read_results(out / "episodes.jsonl"), key=lambda r: r["episode"])
    return [{k: v for k, v in r.items() if k != "seconds"} for r in records], (
        out / "summary.json").read_text()


@pytest.mark.slow
def test_ray_actors_give_the_process_pools_results(tmp_path):
    pooled, pooled_summary = _run(tmp_path / "pool", "process")
    spread, spread_summary = _run(tmp_path / "ray", "ray")
    assert len(pooled) == 8 and spread == pooled
    assert spread_summary == pooled_summary


def test_without_ray_installed_the_executor_says_how_to_get_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray raises ImportError
    with pytest.raises(RoboFollowError, match=r"pip install 'robofollow\[ray\]'"):
        list(results(dict, [1, 2], 2, "ray"))
