"""The benches of bench/ still run: each in its smallest setting, in a process of its own, to
the end with the figures it reports (their values are measured in bench/, never asserted
here). A bench given the test's folder keeps its cache (ROBOFOLLOW_CACHE_DIR) and temporary
folders (TMPDIR) there. eval_bench times the image-free expert only: its `seeing` policy costs
some 40 s even for one episode; train_bench needs JAX (robofollow[train])."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parent.parent


def _bench(*argv: str, folder: Path | None = None) -> str:
    env = dict(os.environ)
    if folder is not None:
        env.update(ROBOFOLLOW_CACHE_DIR=str(folder / "cache"), TMPDIR=str(folder))
        env.pop("ROBOFOLLOW_NO_CACHE", None)
    done = subprocess.run([sys.executable, *argv], cwd=ROOT, capture_output=True, text=True,
                          timeout=600, env=env)
    assert done.returncode == 0, done.stderr
    return done.stdout


def _rows(out: str, *rows: str) -> None:
    for row in rows:
        assert row in out, out


def test_the_compile_bench_runs_to_its_figures():
    """(The checkout itself as the previous code: the pairing runs, whatever the ratios.)"""
    out = _bench("bench/compile_bench.py", "--runs", "1", "--baseline", str(ROOT))
    for row in ("load and check", "generate splits", "audit", "render outputs",
                "write outputs", "previous   ratio", "cold ", "unchanged ", "one spec edited ",
                "scene4 alone, edited ", "scene4 alone, unchanged ", "start-up"):
        assert row in out, out


def test_the_eval_bench_runs_to_its_figures(tmp_path):
    figures = tmp_path / "figures.json"
    out = _bench("bench/eval_bench.py", "--runs", "1", "--expert-episodes", "1", "--policies",
                 "expert", "--json", str(figures), folder=tmp_path)
    assert "expert  1 worker(s)" in out and "expert  2 worker(s)" in out, out
    found = json.loads(figures.read_text())
    assert found["expert_1"]["mean_intent"] == 1.0 and found["expert_2"]["episodes_per_min"] > 0


def test_the_parse_bench_runs_to_its_figures(tmp_path):
    out = _bench("bench/parse_bench.py", "--runs", "1", "--repeat", "1", folder=tmp_path)
    _rows(out, "instructions: 229 (training) x 1 per run, 1 runs", "parser build (once):",
          "parse rate: median")


def test_the_env_start_bench_runs_to_its_figures(tmp_path):
    out = _bench("bench/env_start_bench.py", "--cold", "1", "--warm", "1", folder=tmp_path)
    for name in ("cold", "warm"):
        _rows(out, f"{name:<5} (1 runs, medians): import ")
    _rows(out, "construct ", "reset ", "construct+reset ")


def test_the_expert_start_bench_runs_to_its_figures(tmp_path):
    out = _bench("bench/expert_start_bench.py", "--runs", "1", folder=tmp_path)
    _rows(out, "scene6/L0/red_cube_on_purple_label#r1 on a warm cache, median of 1",
          "start (to the first simulated step)", "the whole command, episode included",
          "a bare Python start")


def test_the_expert_success_bench_runs_to_its_figures(tmp_path):
    results = tmp_path / "results.json"
    out = _bench("bench/expert_success.py", "--tasks", "scene2/L0/pickup_left_cube", "--rounds",
                 "1", "--workers", "1", "--json", str(results), folder=tmp_path)
    _rows(out, "expert scored in full (% of episodes), 1 episodes, 1 workers", "scene2 ",
          "overall ", "mean Intent ", "failures: ")
    assert [r["episode"] for r in json.loads(results.read_text())] == \
        ["scene2/L0/pickup_left_cube#r1"]


def test_the_generate_bench_runs_to_its_figures(tmp_path):
    figures = tmp_path / "figures.json"
    out = _bench("bench/generate_bench.py", "--runs", "1", "--tasks", "1", "--episodes-per-task",
                 "1", "--projection-tasks", "1", "--json", str(figures), folder=tmp_path)
    _rows(out, "1 tasks x 1 demonstrations, lerobot-v2.1", "1 worker(s):", "2 worker(s):",
          "bare physics + 3 renders of the same frames:", "full set: ")
    found = json.loads(figures.read_text())
    assert found["workers_1"]["frames"] == found["workers_2"]["frames"] > 0


def test_the_oracle_bench_runs_to_its_figures(tmp_path):
    out = _bench("bench/oracle_bench.py", "--repeats", "1", folder=tmp_path)
    _rows(out, "alone ms", "+ did-instead ms", "scene1/L0/pickup_yellow_block_2#r1 ",
          "scene4/L0/s41_if_bowl_nonempty_then_l_pick_blue_else_r_stack#r1 ",
          "median over kinds: ")


def test_the_release_bench_runs_to_its_figures(tmp_path):
    figures = tmp_path / "figures.json"
    out = _bench("bench/release_bench.py", "--runs", "1", "--json", str(figures),
                 folder=tmp_path)
    _rows(out, "release v1: benchmark.jsonl.gz ", "fresh process: load", "eval start, release",
          "eval start, working compile", "eval start-up, release / working compile")
    assert set(json.loads(figures.read_text())) == {"size", "medians", "ratio"}


def test_the_sim_bench_runs_to_its_figures(tmp_path):
    out = _bench("bench/sim_bench.py", "--runs", "1", "--steps", "5", folder=tmp_path)
    _rows(out, "scene scene4/scene4_1, 1 runs", "raw physics:", "env, 1 process:",
          "env, 2 processes together:", "bare MuJoCo, same work:", "env cost / bare cost:")


def test_the_train_bench_runs_to_its_figures(tmp_path):
    pytest.importorskip("jax")
    out = _bench("bench/train_bench.py", "--runs", "1", "--steps", "1", "--kinds", "text",
                 folder=tmp_path)
    _rows(out, "median of 1 runs of 1 steps", "samples/s", "act() ms", "\ntext         1 ")
