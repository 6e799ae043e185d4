"""Run reports and comparisons, from hand-made result records."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from robofollow.cli import main
from robofollow.eval.reports.report import (
    compare_reports,
    comparison_markdown,
    write_report,
)
from robofollow.eval.reports.report_data import report_data
from robofollow.eval.running.saved_run import RunReadError
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
                                           "other branch": 0.0, "nothing moved": 0.0,
                                           "moved but touched nothing": 0.0,
                                           "handled objects in no trained way": 50.0}
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
    assert page.startswith("<!doctype html>") and "tasks.html" in page
    assert "background: rgb(105, 255, 105)" in page  # IS 100 shaded
    assert "<h3>scene2</h3>" in (run / "tasks.html").read_text()  # the matrices


def test_clipped_actions_are_counted_and_shown_only_when_there_are_some(run):
    assert "joint limits" not in write_report(run)[0].read_text()
    lines = [dict(r, clipped=c) for r, c in zip(RESULTS, (0, 12, 3, 0), strict=True)]
    (run / "episodes.jsonl").write_text("".join(json.dumps(r) + "\n" for r in lines))
    lines = [dict(r, steps=100) for r in lines]
    (run / "episodes.jsonl").write_text("".join(json.dumps(r) + "\n" for r in lines))
    said = ("15 actions (3.8% of the 400 actions executed) in 2 of 4 episodes (50%) asked for "
            "a joint past its limit")
    assert report_data("mine", OPTIONS, lines)["clipping"].startswith(said)
    markdown, html = write_report(run)
    assert said in " ".join(markdown.read_text().split())
    assert "<h2>Targets past the joint limits</h2>" in html.read_text()


def test_records_with_references_read_intent_against_chance(run):
    lines = [dict(r, chance={"IS": 0.25, "CR": 0.125}, followed_intent=0.5) for r in RESULTS]
    (run / "episodes.jsonl").write_text("".join(json.dumps(r) + "\n" for r in lines))
    markdown, html = write_report(run)
    assert "| scene2 | L0 | 100.0 | 25.0 | 12.5 | 50.0 |" in markdown.read_text()
    page = html.read_text()
    assert "<th>ch.</th>" in page and '<td class="note">25.0</td>' in page  # in Table 1
    assert 'class="below"' not in page  # no cell below chance
    (run / "episodes.jsonl").write_text("".join(json.dumps(r) + "\n" for r in RESULTS))
    text = write_report(run)[0].read_text()  # records without references
    assert "Reading Intent against chance" not in text and "chance IS" not in text


def test_two_runs_compare_side_by_side(run, tmp_path, capsys):
    other = tmp_path / "other"
    other.mkdir()
    (other / "run.json").write_text(json.dumps(OPTIONS.to_json()))
    (other / "episodes.jsonl").write_text(json.dumps(
        fake_record("pickup_left_cube", "L0", 0.0, 0.0, False, None)) + "\n")
    found = compare_reports([run, other])
    text = comparison_markdown(found)
    # the cells of the one episode both runs hold; the others left out, said
    assert "| scene2 | L0 | 100.0 | 0.0 | -100.0 |" in text
    assert "| scene2 | L1 |" not in text
    assert found.warnings == [
        (f"{run} holds 3 episode(s) that another run lacks, left out: "
         "scene2/L0/pickup_right_cube#r1, scene2/L1/pickup_right_cube#r1, "
         "scene2/L1/push_left_cube#r1"), "compared on the 1 episodes every run holds"]
    # then the paired differences, B - A, over the one episode both runs have
    assert "## Paired differences: other − mine (intervals over tasks)" in text
    assert "| scene2 | L0 | 0.0 | 100.0 | -100.0 |" in text
    assert main(["report", str(run), str(other), "--out", str(tmp_path / "c.md")]) == 0
    assert (tmp_path / "c.md").read_text() == text
    assert "holds 3 episode(s) that another run lacks" in capsys.readouterr().err
    assert main(["report", str(run), str(other), str(run), "--out", str(tmp_path / "three")]) == 0
    page = (tmp_path / "three" / "comparison.html").read_text()
    assert "mine vs other vs mine" in page and (tmp_path / "three" / "figures" / "runs.svg").is_file()


def test_a_folder_without_a_run_is_a_clear_error(tmp_path):
    with pytest.raises(RunReadError, match="holds no evaluation run"):
        write_report(tmp_path)


# L1: two moved tasks the policy fails, one as-trained task it passes; L3: one of each, the
# moved one half done. The whole cell is neither subset.
MOTION_RECORDS = [
    dict(fake_record("push_left_cube", "L1", 0.0, 0.0, False, None), motion="moved"),
    dict(fake_record("push_right_cube", "L1", 0.5, 0.25, False, None), motion="moved"),
    dict(fake_record("pickup_left_cube", "L1", 1.0, 1.0, True, "instructed"),
         motion="as-trained"),
    dict(fake_record("pickup_right_cube", "L3", 0.5, 0.5, True, "instructed"), motion="moved"),
    dict(fake_record("pickup_left_cube", "L3", 1.0, 0.75, True, "instructed"),
         motion="as-trained"),
    dict(fake_record("pickup_left_cube", "L0", 1.0, 1.0, True, "instructed"), motion=None),
]


def _write(run: Path, records: list[dict]) -> None:
    (run / "episodes.jsonl").write_text("".join(json.dumps(r) + "\n" for r in records))


def test_l1_and_l3_cells_are_split_into_their_moved_and_as_trained_tasks():
    cells = report_data("mine", OPTIONS, MOTION_RECORDS)["cells"]["scene2"]
    assert "by_motion" not in cells["L0"]
    l1, l3 = cells["L1"], cells["L3"]
    assert (l1["IS"], l1["ES"], l1["CR"], l1["episodes"]) == (50.0, 41.67, 33.33, 3)  # unchanged
    moved, trained = l1["by_motion"]["moved"], l1["by_motion"]["as-trained"]
    assert {k: moved[k] for k in ("IS", "ES", "CR", "episodes", "tasks")} == {
        "IS": 25.0, "ES": 12.5, "CR": 0.0, "episodes": 2, "tasks": 2}
    assert {k: trained[k] for k in ("IS", "ES", "CR", "episodes")} == {
        "IS": 100.0, "ES": 100.0, "CR": 100.0, "episodes": 1}
    assert l1["by_motion"]["unknown"] == 0
    assert (l3["by_motion"]["moved"]["ES"], l3["by_motion"]["as-trained"]["ES"]) == (50.0, 75.0)


def test_the_printed_table_gives_moved_and_as_trained_rows_with_their_episodes():
    from robofollow.eval.reports.tables import table_text
    from robofollow.eval.running.runner import summary

    lines = table_text(summary(MOTION_RECORDS, OPTIONS)).splitlines()
    assert max(len(line) for line in lines) <= 80
    scene = next(i for i, line in enumerate(lines) if line.startswith("scene2"))
    # every cell holds fewer than FEW episodes: each is marked, and the mark said
    assert lines[scene].split() == ["scene2", "100", "100", "100*", "50.0", "41.7", "33.3*",
                                    "75.0", "62.5", "100*"]
    assert lines[-2].startswith("*") and "fewer than 20 episodes" in lines[-2]
    moved, trained, counts = lines[scene + 1: scene + 4]
    assert moved.split() == ["moved", "25.0", "12.5", "0.0*", "50.0", "50.0", "100*"]
    assert trained.split() == ["as-trained", "100", "100", "100*", "100", "75.0", "100*"]
    assert counts.split() == ["episodes", "(moved,", "as-trained):", "L1", "2,", "1;", "L3",
                              "1,", "1"]
    from robofollow.eval.reports.tables import LABEL, WIDTH

    # the L1 values in the L1 column (the second: levels L0, L1, L3), the L3 ones in the third
    assert LABEL + WIDTH <= moved.index("25.0") < moved.index("0.0") < LABEL + 2 * WIDTH
    assert LABEL + 2 * WIDTH <= moved.index("50.0") < LABEL + 3 * WIDTH
    assert "motion unknown" not in "\n".join(lines)


def test_the_reports_give_l1_and_l3_for_both_subsets_beside_the_whole(run):
    _write(run, MOTION_RECORDS)
    markdown, html = write_report(run)
    text = markdown.read_text()
    assert "### L1 and L3: moved and as-trained tasks" in text
    assert ("| scene2 | L1 | 50.0 | 41.7 | 33.3 | 3 | 25.0 | 12.5 | 0.0 | 2 | 100.0 | 100.0 "
            "| 100.0 | 1 |") in text
    assert ("| scene2 | L3 | 75.0 | 62.5 | 100.0 | 2 | 50.0 | 50.0 | 100.0 | 1 | 100.0 | 75.0 "
            "| 100.0 | 1 |") in text
    assert "motion unknown" not in text
    assert "| scene2 | 100.0 | 100.0 | 100.0 | 50.0 | 41.7 | 33.3 | 75.0 | 62.5 | 100.0 |" in text
    page = html.read_text()
    assert ("<tr><td>scene2</td><td>L1</td><td>50.0</td><td>41.7</td><td>33.3</td><td>3</td>"
            "<td>25.0</td><td>12.5</td><td>0.0</td><td>2</td><td>100.0</td><td>100.0</td>"
            "<td>100.0</td><td>1</td></tr>") in page
    summary_cells = json.loads(json.dumps(report_data("mine", OPTIONS, MOTION_RECORDS)[
        "summary"]))["cells"]["scene2"]
    assert summary_cells["L3"]["by_motion"]["moved"]["IS"] == 50.0


def test_records_without_their_motion_show_it_unknown_or_take_the_compiled_one(run):
    older = [{k: v for k, v in r.items() if k != "motion"} for r in MOTION_RECORDS]
    _write(run, older)
    text = write_report(run)[0].read_text()
    assert ("| scene2 | L1 | 50.0 | 41.7 | 33.3 | 3 | - | - | - | 0 | - | - | - | 0 | 3 |"
            in text)
    from robofollow.eval.reports.tables import table_text
    from robofollow.eval.running.runner import summary

    printed = table_text(summary(older, OPTIONS))
    assert "motion unknown: L1 3, L3 2 (records" in " ".join(printed.split())
    assert [line.split()[:3] for line in printed.splitlines()
            if line.strip().startswith("moved")] == [["moved", "-", "-"]]
    motions = {r["episode"]: r["motion"] for r in MOTION_RECORDS}
    text = write_report(run, motions)[0].read_text()
    assert ("| scene2 | L1 | 50.0 | 41.7 | 33.3 | 3 | 25.0 | 12.5 | 0.0 | 2 | 100.0 | 100.0 "
            "| 100.0 | 1 |") in text


def test_the_report_command_says_when_it_cannot_tell_the_motion(run, capsys, tmp_path):
    _write(run, [{k: v for k, v in r.items() if k != "motion"} for r in MOTION_RECORDS])
    specs = tmp_path / "specs"
    specs.mkdir()
    from tests.spec_helpers import VALID

    (specs / "demo.rf").write_text(VALID)
    assert main(["report", str(run), "--specs", str(specs)]) == 0
    assert "5 L1/L3 records do not say whether their task's motion moved" in (
        capsys.readouterr().err)
    assert "| 3 | - | - | - | 0 | - | - | - | 0 | 3 |" in (run / "report.md").read_text()


def test_comparisons_give_the_moved_and_as_trained_rows(run, tmp_path):
    other = tmp_path / "other"
    other.mkdir()
    (other / "run.json").write_text(json.dumps(OPTIONS.to_json()))
    _write(other, [dict(r, intent_score=1.0) for r in MOTION_RECORDS])
    _write(run, MOTION_RECORDS)
    text = comparison_markdown(compare_reports([run, other]))
    assert "| scene2 | L1 | 50.0 | 100.0 | +50.0 |" in text
    assert "| scene2 | L1 moved | 25.0 | 100.0 | +75.0 |" in text
    assert "| scene2 | L1 as-trained | 100.0 | 100.0 | +0.0 |" in text
    assert "| scene2 | L3 moved | 50.0 | 100.0 | +50.0 |" in text
    assert "L0 moved" not in text


def test_the_report_command_takes_the_motion_of_older_records_from_the_compiled_episodes(
        tmp_path, monkeypatch):
    from dataclasses import replace

    from robofollow.benchmark.pipeline import compile_specs
    from robofollow.benchmark.rounds import all_episodes
    from robofollow.resources import builtin_specs

    monkeypatch.setenv("ROBOFOLLOW_CACHE_DIR", str(tmp_path / "cache"))
    specs = tmp_path / "specs"
    specs.mkdir()
    (specs / "scene1.rf").write_text((builtin_specs() / "scene1.rf").read_text())
    compiled = compile_specs(specs)
    chosen = {}
    for episode in all_episodes(compiled):
        if episode.level == "L1" and episode.round == 1:
            chosen.setdefault(episode.motion, episode)
    records = []
    for kind, score in (("moved", 0.0), ("as-trained", 1.0)):
        episode = chosen[kind]
        label = episode.task.split("/", 2)[-1]
        record = fake_record(label, "L1", score, score, bool(score), None)
        records.append(dict(record, scene="scene1", episode=episode.id, task=episode.task))
    run = tmp_path / "older"
    run.mkdir()
    options = replace(OPTIONS, scenes=("scene1",), spec_digest=compiled.spec.digest)
    (run / "run.json").write_text(json.dumps(options.to_json()))
    _write(run, records)
    assert main(["report", str(run), "--specs", str(specs)]) == 0
    assert ("| scene1 | L1 | 50.0 | 50.0 | 50.0 | 2 | 0.0 | 0.0 | 0.0 | 1 | 100.0 | 100.0 "
            "| 100.0 | 1 |") in (run / "report.md").read_text()


def test_the_drop_from_l0_skips_an_l1_that_pairs_with_no_l0_task():
    from robofollow.eval.statistics.drops import level_drops

    def record(task, level, score):
        return {"scene": "scene2", "level": level, "task": f"scene2/{level}/{task}",
                "intent_score": score, "execution_score": score, "complete": score > 0.5}

    results = [record("a", "L0", 1.0), record("b", "L0", 1.0), record("c@x", "L1", 0.0),
               record("n1", "L2", 0.0), record("n2", "L2", 0.5)]
    rows = level_drops(results)
    assert [(r["level"], r["paired"]) for r in rows] == [("L2", False)]
    assert rows[0]["IS"]["drop"] == 75.0
    paired = level_drops(results + [record("a@x", "L1", 0.25)])
    assert paired[0]["level"] == "L1" and paired[0]["tasks"] == (1, 1)
    assert paired[0]["IS"]["drop"] == 75.0
