"""The benches of bench/ still run: each in its smallest setting, in a process of its own, to
the end with the figures it reports (their values are measured in bench/, never asserted
here). eval_bench times the image-free expert only: its `seeing` policy costs some 40 s even
for one episode."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parent.parent


def _bench(*argv: str) -> str:
    done = subprocess.run([sys.executable, *argv], cwd=ROOT, capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr
    return done.stdout


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
                 "expert", "--json", str(figures))
    assert "expert  1 worker(s)" in out and "expert  2 worker(s)" in out, out
    found = json.loads(figures.read_text())
    assert found["expert_1"]["mean_intent"] == 1.0 and found["expert_2"]["episodes_per_min"] > 0
