"""Run reports and comparisons, from hand-made result records."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from robofollow.cli import main
from robofollow.eval.report import ReportError, comparison, report_data, write_report
from tests.report_helpers import OPTIONS, fake_record

RESULTS = [
    fake_record("pickup_left_cube", "L0", 1.0, 1.0, True, "instructed"),
    fake_record("pickup_right_cube", "L0", 1.0, 0.0, False, None, "the cube slipped"),
    fake_record("pickup_right_cube", "L1", 0.0, 0.0, False, "pickup_left_cube",
            "the left arm first closed on large_blue_cube"),
    fake_record("push_left_cube", "L1", 0.0, 0.0, False, None, "never closed",
            error="step 50: the policy raised RuntimeError: boom"),
]


@pytest.fixture
def run(tmp_path) -> Path:
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / "run.json").write_text(json.dumps(OPTIONS.to_json()))
    (folder / "episodes.jsonl").write_text("".join(json.dumps(r) + "\n" for r in RESULTS))
    return folder


def test_report_data_counts_what_the_policy_did_and_where_it_failed_first():
    data = report_data("mine", OPTIONS, RESULTS)
    assert data["cells"]["scene2"]["L0"]["IS"] == 100.0
    assert data["cells"]["scene2"]["L0"]["ES"] == 50.0
    assert data["did"]["scene2"]["L1"] == {"completed": 0.0, "as instructed": 0.0,
                                           "another training task": 50.0,
                                           "other branch": 0.0, "unrecognised": 50.0}
    assert data["did"]["scene2"]["L0"]["completed"] == 50.0
    assert data["confusions"] == [(("scene2/L1/pickup_right_cube", "pickup_left_cube"), 1)]
    [source] = data["first_failures"]
    assert source["stage"] == "source" and source["episodes"] == 3
    assert data["errors"] == [("the policy raised RuntimeError: boom", 1)]
    assert data["matrices"]["scene2"]["counts"]["scene2/L1/pickup_right_cube"] == {
        "pickup_left_cube": 1}


def test_the_report_files_show_table_gap_confusions_and_reasons(run):
    markdown, html = write_report(run)
    text = markdown.read_text()
    assert "| scene2 | 100.0 | 50.0 | 50.0 | 0.0 | 0.0 | 0.0 |" in text
    assert "| scene2 | 50.0 | 0.0 |" in text  # Intent minus Execution, L0 and L1
    assert "| L1 · Use your left arm to pickup right cube. | pickup_left_cube | 1 |" in text
    assert "the cube slipped (1)" in text
    page = html.read_text()
    assert page.startswith("<!doctype html>") and "<h3>scene2</h3>" in page
    assert "background: rgb(105, 255, 105)" in page  # IS 100 shaded


def test_clipped_actions_are_counted_and_shown_only_when_there_are_some(run):
    assert "joint limits" not in write_report(run)[0].read_text()
    lines = [dict(r, clipped=c) for r, c in zip(RESULTS, (0, 12, 3, 0), strict=True)]
    (run / "episodes.jsonl").write_text("".join(json.dumps(r) + "\n" for r in lines))
    assert report_data("mine", OPTIONS, lines)["clipped"] == {"actions": 15, "episodes": 2}
    markdown, html = write_report(run)
    assert "15 actions in 2 episodes asked for a joint past its limit" in markdown.read_text()
    assert "<h2>Targets past the joint limits</h2>" in html.read_text()


def test_records_with_references_read_intent_against_chance(run):
    lines = [dict(r, chance={"IS": 0.25, "CR": 0.125}, followed_intent=0.5) for r in RESULTS]
    (run / "episodes.jsonl").write_text("".join(json.dumps(r) + "\n" for r in lines))
    markdown, html = write_report(run)
    assert "| scene2 | L0 | 100.0 | 25.0 | 12.5 | 50.0 |" in markdown.read_text()
    assert "<td>scene2</td><td>L1</td><td>0.0</td><td>25.0</td><td>12.5</td><td>50.0</td>" in (
        html.read_text())
    (run / "episodes.jsonl").write_text("".join(json.dumps(r) + "\n" for r in RESULTS))
    assert "chance" not in write_report(run)[0].read_text()  # records without references


def test_two_runs_compare_side_by_side(run, tmp_path, capsys):
    other = tmp_path / "other"
    other.mkdir()
    (other / "run.json").write_text(json.dumps(OPTIONS.to_json()))
    (other / "episodes.jsonl").write_text(json.dumps(
        fake_record("pickup_left_cube", "L0", 0.0, 0.0, False, None)) + "\n")
    text = comparison([run, other])
    assert "| scene2 | L0 | 100.0 | 0.0 | -100.0 |" in text
    assert "| scene2 | L1 | 0.0 | - | - |" in text
    assert main(["report", str(run), str(other), "--out", str(tmp_path / "c.md")]) == 0
    assert (tmp_path / "c.md").read_text() == text
    assert main(["report", str(run), str(other), str(run)]) == 1
    assert "one run, or two to compare" in capsys.readouterr().err


def test_a_folder_without_a_run_is_a_clear_error(tmp_path):
    with pytest.raises(ReportError, match="holds no evaluation run"):
        write_report(tmp_path)
