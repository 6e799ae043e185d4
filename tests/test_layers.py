"""The house's layers, as the import-linter contracts in pyproject.toml state them."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
LINT = [sys.executable, "-c", "import sys; from importlinter.cli import lint_imports_command; "
                              "sys.exit(lint_imports_command())"]


def lint(root: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(root)}
    return subprocess.run([*LINT, "--no-cache"], cwd=root, env=env, capture_output=True,
                          text=True, timeout=120)


def test_the_code_keeps_every_contract():
    result = lint(ROOT)
    assert result.returncode == 0, result.stdout + result.stderr


@pytest.mark.parametrize(("module", "bad_import", "broken"), [
    ("compiler/language/lf.py", "import robofollow.eval.reports.report", "Data flows one way"),
    ("eval/statistics/metrics.py", "import mujoco", "no MuJoCo"),
    ("audit/entropy.py", "import robofollow.oracle.score", "robofollow.audit"),
    ("eval/running/run_folder.py", "import robofollow.eval.running.runner", "No import cycles"),
    # the compiler's rooms: up a floor, and across to the room beside
    ("compiler/language/lf.py", "import robofollow.compiler.scene.spec", "The compiler's rooms"),
    ("compiler/scene/world.py", "import robofollow.compiler.splits.generator",
     "The compiler's rooms"),
    ("compiler/authoring/layouts.py", "import robofollow.compiler.planning.goals",
     "The compiler's rooms"),
    ("compiler/planning/goals.py", "import robofollow.compiler.authoring.spec_loader",
     "The compiler's rooms"),
    # evaluation's rooms: the clients never import the servers, the statistics never the runner
    ("eval/policies/tcp_client.py", "import robofollow.eval.serving.tcp_server",
     "Evaluation's rooms"),
    ("eval/statistics/paired.py", "import robofollow.eval.running.runner", "Evaluation's rooms"),
    ("eval/statistics/metrics.py", "import robofollow.eval.policies.policy",
     "Evaluation's rooms"),
    ("eval/serving/serving.py", "import robofollow.eval.reports.report", "Evaluation's rooms"),
    ("eval/protocols/wire.py", "import robofollow.eval.policies.policy", "Evaluation's rooms"),
    ("eval/statistics/intervals.py", "import robofollow.files", "numbers in, numbers out"),
])
def test_a_bad_import_breaks_a_contract(tmp_path, module, bad_import, broken):
    shutil.copytree(ROOT / "robofollow", tmp_path / "robofollow",
                    ignore=shutil.ignore_patterns("__pycache__", "baselines"))
    shutil.copy(ROOT / "pyproject.toml", tmp_path)
    path = tmp_path / "robofollow" / module
    path.write_text(path.read_text(encoding="utf-8") + f"\n{bad_import}\n", encoding="utf-8")
    result = lint(tmp_path)
    assert result.returncode != 0
    assert "BROKEN" in result.stdout and broken in result.stdout, result.stdout
