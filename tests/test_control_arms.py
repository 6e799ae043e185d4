"""`robofollow eval --controls empty,shuffled`: the control arms run on the very same episodes
in RUN/controls/<mode>, each a run of its own, and the report and the command give the
language effect (instructed - control) with paired intervals over tasks; the report also gives
the drop from L0 with intervals."""

from __future__ import annotations

import json

import pytest

from robofollow.cli import main
from robofollow.eval.reports.comparison import compare_runs, run_scores

pytestmark = pytest.mark.slow


def test_control_arms_run_the_same_episodes_and_report_the_language_effect(tmp_path, capsys):
    run = tmp_path / "text"
    assert main(["eval", "--policy", "baseline:scene2-text", "--scenes", "scene2",
                 "--levels", "L0,L1", "--controls", "empty,shuffled", "--rounds", "2",
                 "--sample", "2", "--workers", "1", "--quiet", "--out", str(run)]) == 0
    out = capsys.readouterr().out
    assert "language effect, instructed - empty instructions (Intent):" in out
    assert "language effect, instructed - shuffled instructions (Intent):" in out
    episodes = {row["episode"]: row["hash"] for row in run_scores(run)}
    assert len(episodes) == 8
    for mode in ("empty", "shuffled"):
        arm = tmp_path / "text" / "controls" / mode
        assert json.loads((arm / "run.json").read_text())["instruction_mode"] == mode
        assert (arm / "summary.json").is_file() and (arm / "report.md").is_file()
        assert {row["episode"]: row["hash"] for row in run_scores(arm)} == episodes
        result = compare_runs(run, arm, ("instructed", mode))
        assert result["pairing"]["pairs"] == 8 and not result["warnings"]
    report = (run / "report.md").read_text()
    assert "## Language effect: instructed − empty instructions" in report
    assert "## Language effect: instructed − shuffled instructions" in report
    assert "## The drop from L0, with intervals over tasks" in report
    assert "| scene2 | L1 | paired |" in report


def test_a_control_arm_must_be_another_instruction_mode(tmp_path, capsys):
    for controls, message in (("empty,shufled", ("unknown control arm shufled; did you mean "
                                                 "shuffled?")),
                              ("empty", "the run itself gives empty instructions")):
        assert main(["eval", "--policy", "noop", "--controls", controls, "--instruction-mode",
                     "empty", "--out", str(tmp_path / "run")]) == 2
        err = capsys.readouterr().err
        assert message in err and "Traceback" not in err, err
        assert not (tmp_path / "run").exists()
