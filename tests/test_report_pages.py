"""What a researcher reads: shipped runs rebuild and compare from their score files, cells
below chance are flagged, videos of every level reach their cell, 'unrecognised' says what
happened, Table 1 exports for a paper, and a mistyped eval leaves nothing behind."""

from __future__ import annotations

import csv
import io
import json
import shutil
from dataclasses import replace
from pathlib import Path
from xml.etree import ElementTree

import pytest

from robofollow.cli import main
from robofollow.eval.reports.report import ReportError, compare_reports, write_report
from robofollow.eval.reports.report_data import report_data
from robofollow.eval.running.outcomes import (
    STILL,
    UNRECORDED,
    UNTOUCHED,
    UNTRAINED,
    closest,
)
from robofollow.eval.running.run_folder import RESULTS, RUN_FILE, SCORES, prepare
from robofollow.eval.running.runner import summary
from robofollow.eval.running.scores import write_scores
from robofollow.provenance import environment
from tests.report_helpers import OPTIONS, fake_record

ENVIRONMENT = environment()

SHIPPED = Path(__file__).resolve().parent.parent / "docs" / "results" / "baselines"


def _folder(path: Path, records: list[dict], options=OPTIONS) -> Path:
    path.mkdir(parents=True)
    (path / RUN_FILE).write_text(json.dumps(options.to_json()))
    (path / RESULTS).write_text("".join(json.dumps(r) + "\n" for r in records))
    (path / "summary.json").write_text(json.dumps(summary(records, options)))
    write_scores(path / SCORES, records)
    return path


def _records(level: str, tasks: int, intent: float, chance: float, name: str = "pickup",
             **extra) -> list[dict]:
    found = []
    for number in range(tasks):
        record = fake_record(f"{name}_{number}@scene2_{number % 3}", level, intent, intent,
                             intent == 1.0, "instructed" if intent == 1.0 else None,
                             reason=f"never grasped object {number}",
                             layout=f"scene2_{number % 3}")
        found.append(dict(record, chance={"IS": chance, "CR": chance}, followed_intent=1.0,
                          clipped=number, steps=100, **extra))
    return found


def test_a_cell_whose_interval_lies_under_chance_is_flagged_in_every_format(tmp_path):
    records = _records("L0", 12, 1.0, 0.25) + _records("L1", 20, 0.0, 0.25)
    run = _folder(tmp_path / "run", records)
    data = report_data("run", OPTIONS, records)
    assert [(c["level"], c["below_chance"]) for c in data["table"]] == [("L0", False),
                                                                        ("L1", True)]
    assert any(line.startswith("Intent below chance") and "scene2 L1 0.0" in line
               for line in data["findings"])
    markdown, html = write_report(run)
    assert "| 0.0 ▼ |" in markdown.read_text()
    page = html.read_text()
    assert page.count('class="below"') == 1 and "<th>ch.</th>" in page
    # a one-task cell is judged on its Wilson interval over episodes
    one = _records("L1", 1, 0.0, 0.25)
    assert not report_data("one", OPTIONS, one)["table"][0]["below_chance"]  # [0, 79] of 1


def test_failure_videos_of_every_level_reach_their_cell_with_a_caption(tmp_path):
    ids = {"L1": "pickup_cube@scene2_1", "L3": "pickup_cube@scene2_1/referents-1f2e"}
    records = []
    for level, task in ids.items():
        record = fake_record(task, level, 0.0, 0.0, False, None, reason="never grasped it")
        name = record["episode"].replace("/", "__").replace("#", "_") + ".mp4"  # as the runner
        records.append(dict(record, video=f"videos/{name}"))
    data = report_data("run", OPTIONS, records)
    assert sorted(data["videos"]) == [("scene2", "L1"), ("scene2", "L3")]
    run = _folder(tmp_path / "run", records)
    page = write_report(run)[1].read_text()
    for record in records:
        assert f'<video src="{record["video"]}"' in page
    assert page.count("first failed: source: never grasped it") == 2
    assert "did: handled objects in no trained way" in page


def test_unrecognised_behaviour_says_what_happened():
    def behaviour(description, **extra):
        return {"executed_behaviour": {"match": None, "description": description, **extra}}

    assert closest(behaviour("nothing moved", arms_moved=False)) == STILL
    assert closest(behaviour("the arms moved but touched nothing", arms_moved=True)) == UNTOUCHED
    assert closest(behaviour("nothing moved")) == UNRECORDED  # older records: touched nothing
    assert closest(behaviour("the left arm pushed small_red_cube (frame 51)",
                             arms_moved=True)) == UNTRAINED
    assert closest({"executed_behaviour": {"match": "instructed"}}) == "as instructed"
    assert closest({"executed_behaviour": {"match": "pickup_left_cube"}}) == "pickup_left_cube"
    assert closest({"did": STILL}) == STILL  # a compact record says it already


def test_a_report_rebuilt_from_the_score_file_equals_the_one_from_full_records(tmp_path):
    records = (_records("L0", 6, 1.0, 0.25) + _records("L1", 9, 0.0, 0.25)
               + _records("L1", 3, 1.0, 0.25, name="place"))
    full = _folder(tmp_path / "a" / "run", records)
    kept = tmp_path / "b" / "run"
    kept.mkdir(parents=True)
    for name in (RUN_FILE, "summary.json", SCORES):
        shutil.copy(full / name, kept / name)
    for folder in (full, kept):
        write_report(folder)
    for page in ("report.md", "report.html", "tasks.html"):
        assert (full / page).read_text() == (kept / page).read_text(), page
    assert sorted(p.name for p in (kept / "figures").iterdir()) == sorted(
        p.name for p in (full / "figures").iterdir())
    for figure in (full / "figures").iterdir():  # the same bytes, rebuilt anywhere
        assert figure.read_bytes() == (kept / "figures" / figure.name).read_bytes()


def test_a_report_is_never_rebuilt_from_fewer_episodes_than_its_summary(tmp_path):
    records = _records("L0", 4, 1.0, 0.25)
    run = _folder(tmp_path / "run", records)
    write_report(run)
    before = (run / "report.md").read_text()
    (run / RESULTS).write_text(json.dumps(records[0]) + "\n")  # one of four left
    with pytest.raises(ReportError, match="summary counts 4 episodes but only 1 are here"):
        write_report(run)
    assert (run / "report.md").read_text() == before


@pytest.mark.parametrize("name", ["scene2-text", "scene2-blind"])
def test_rebuilding_a_shipped_run_keeps_its_report(tmp_path, name):
    copy = tmp_path / name
    shutil.copytree(SHIPPED / name, copy)
    assert not (copy / RESULTS).exists()  # a shipped run keeps its scores only
    assert main(["report", str(copy)]) == 0
    for page in ("report.md", "report.html", "tasks.html"):
        assert (copy / page).read_text() == (SHIPPED / name / page).read_text(), page
    cells = json.loads((SHIPPED / name / "summary.json").read_text())["cells"]["scene2"]
    assert f"| scene2 | {cells['L0']['IS']:.1f}" in (copy / "report.md").read_text()


def test_the_shipped_baselines_compare_cell_by_cell(capsys):
    text, blind = SHIPPED / "scene2-text", SHIPPED / "scene2-blind"
    assert main(["report", str(text), str(blind)]) == 0
    out = capsys.readouterr().out
    a = json.loads((text / "summary.json").read_text())["cells"]["scene2"]
    b = json.loads((blind / "summary.json").read_text())["cells"]["scene2"]
    for level in ("L0", "L1", "L2", "L3"):
        row = (f"| scene2 | {level} | {a[level]['IS']:.1f} | {b[level]['IS']:.1f} | "
               f"{b[level]['IS'] - a[level]['IS']:+.1f} |")
        assert row in out, row
    assert "## Paired differences: scene2-blind − scene2-text" in out
    assert "1840 paired episodes" in out


def test_comparing_runs_over_different_episodes_warns_and_keeps_the_common_ones(tmp_path):
    a = _folder(tmp_path / "a", _records("L0", 4, 1.0, 0.25) + _records("L1", 4, 0.0, 0.25))
    b = _folder(tmp_path / "b", _records("L0", 4, 0.0, 0.25))
    found = compare_reports([a, b])
    assert found.warnings[0].startswith(f"{a} holds 4 episode(s) that another run lacks")
    assert found.warnings[-1] == "compared on the 4 episodes every run holds"
    assert [set(t["cells"]["scene2"]) for t in found.tables] == [{"L0"}, {"L0"}]


def test_a_run_without_episodes_gets_a_report_without_figures(tmp_path):
    run = _folder(tmp_path / "run", [])
    markdown, html = write_report(run)
    assert "0 episodes" in markdown.read_text() and not (run / "figures").exists()


def test_table_1_exports_with_its_intervals(tmp_path):
    records = _records("L0", 6, 1.0, 0.25) + _records("L1", 6, 0.0, 0.25)
    run = _folder(tmp_path / "run", records, replace(OPTIONS, policy="runs/my_ckpt&v2"))
    assert main(["report", str(run), "--export", "csv", "--export", "latex"]) == 0
    rows = list(csv.DictReader(io.StringIO((run / "table1.csv").read_text())))
    assert [(r["scene"], r["level"], r["IS"], r["tasks"]) for r in rows] == [
        ("scene2", "L0", "100.0", "6"), ("scene2", "L1", "0.0", "6"), ("avg", "", "50.0", "")]
    assert float(rows[1]["IS_low"]) == 0.0 and float(rows[1]["IS_high"]) > 0
    assert rows[0]["chance_IS"] == "25.0"
    latex = (run / "table1.tex").read_text()
    assert r"\multicolumn{3}{c}{L0}" in latex and r"\makecell{100.0\\ \tiny[" in latex
    assert r"runs/my\_ckpt\&v2" in latex and "95\\% intervals" in latex  # escaped
    assert latex.count(r"\\") >= 4 and r"\end{tabular}" in latex


def test_a_misspelt_policy_or_name_leaves_no_folder_and_says_the_right_one(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["eval", "--policy", "blnd", "--out", str(out)]) == 1
    assert "did you mean 'blind'?" in capsys.readouterr().err
    assert main(["eval", "--policy", "baseline:scene2-txt", "--out", str(out)]) == 1
    assert "did you mean 'scene2-text'?" in capsys.readouterr().err
    assert main(["eval", "--policy", "blind", "--scenes", "scen2", "--out", str(out)]) == 2
    assert "did you mean scene2?" in capsys.readouterr().err
    assert main(["eval", "--policy", "blind", "--levels", "l5", "--out", str(out)]) == 2
    assert not out.exists()


def test_a_run_folder_without_a_finished_episode_is_as_good_as_empty(tmp_path):
    out = tmp_path / "run"
    out.mkdir()
    (out / RUN_FILE).write_text(json.dumps(dict(OPTIONS.to_json(), policy="blnd")))
    prepare(out, OPTIONS.to_json(), resume=False, environment=ENVIRONMENT)  # as good as empty
    assert json.loads((out / RUN_FILE).read_text())["policy"] == OPTIONS.policy
    (out / RESULTS).write_text(json.dumps(fake_record("a", "L0", 1, 1, True, None)) + "\n")
    with pytest.raises(Exception, match="already holds a run"):
        prepare(out, OPTIONS.to_json(), resume=False, environment=ENVIRONMENT)
    # a shipped run keeps its summary and scores, not its records: it holds a run
    shipped = _folder(tmp_path / "shipped", _records("L0", 2, 1.0, 0.25))
    (shipped / RESULTS).unlink()
    for resume in (False, True):
        with pytest.raises(Exception, match="already holds a run|keeps only its scores"):
            prepare(shipped, dict(OPTIONS.to_json(), policy="noop"), resume=resume,
                    environment=ENVIRONMENT)


def test_eval_videos_of_l3_episodes_are_captioned_and_shown_beside_their_cell(tmp_path):
    from robofollow.compiled_cache import load
    from robofollow.resources import builtin_specs
    from robofollow.sim.video import CAPTION_HEIGHT, read_frames

    task = next(t for t in load(builtin_specs()).task_ids if t.startswith("scene2/L3/"))
    out = tmp_path / "run"
    assert main(["eval", "--policy", "noop", "--tasks", task, "--rounds", "1", "--workers",
                 "1", "--quiet", "--video", "failures", "--specs", str(builtin_specs()),
                 "--out", str(out)]) == 0
    [video] = (out / "videos").iterdir()
    assert "@" in video.name
    frames = read_frames(video)
    assert frames[0].shape[0] == 240 + CAPTION_HEIGHT and len(frames) > 100
    assert frames[0][-CAPTION_HEIGHT:].mean() < frames[0][:240].mean()  # the dark band
    page = (out / "report.html").read_text()
    assert f'<video src="videos/{video.name}"' in page and "<h3>scene2 L3</h3>" in page


def test_report_md_carries_no_markup_from_a_run_or_its_policy(tmp_path):
    """A folder name, a policy name and a policy's error are outside text: report.md shows
    them on their line, with no tag a markdown renderer would read and no code span they
    can close early."""
    options = replace(OPTIONS, policy="mine:make`<img src=x onerror=alert(1)>")
    records = [dict(r, error="step 3: <script>alert(2)</script>\nforged line")
               for r in _records("L0", 2, 0.0, 0.25)]
    run = _folder(tmp_path / "<b>run\n# forged heading", records, options)
    write_report(run)
    text = (run / "report.md").read_text()
    span = "``mine:make`<img src=x onerror=alert(1)>``"  # (a code span shows it as text)
    assert f"Policy {span}," in text
    outside = text.replace(span, "")
    assert "<img" not in outside and "<script" not in outside and "<b>" not in outside
    assert "\n# forged heading" not in text and "\nforged line" not in text
    assert "# RoboFollow evaluation: &lt;b&gt;run # forged heading" in text
    assert "- &lt;script&gt;alert(2)&lt;/script&gt; forged line (2)" in text


def test_a_report_rebuild_cut_short_leaves_every_figure_whole(tmp_path, monkeypatch):
    """A rebuild killed while a figure is written (here: the drawing dies part-way, after its
    output was opened) leaves the previous figures as they were, none empty."""
    from matplotlib.figure import Figure

    copy = tmp_path / "scene2-text"
    shutil.copytree(SHIPPED / "scene2-text", copy)
    before = {p.name: p.read_bytes() for p in (copy / "figures").iterdir()}

    def dying(self, target, **options):
        if isinstance(target, (str, Path)):
            open(target, "wb").close()  # (as far as a kill after open would get)
        else:
            target.write(b"<svg")
        raise KeyboardInterrupt

    monkeypatch.setattr(Figure, "savefig", dying)
    with pytest.raises(KeyboardInterrupt):
        write_report(copy)
    assert {p.name: p.read_bytes() for p in (copy / "figures").iterdir()} == before


def test_a_report_defines_the_levels_and_says_when_no_stage_failed(tmp_path):
    """What a newcomer asked of the expert's report: every level said in words beside Table 1,
    and no empty table of first failed stages when every episode passed; the levels figure
    keeps its legend beside the panels, off the bars."""
    passed = _folder(tmp_path / "passed", _records("L0", 3, 1.0, 0.25))
    failed = _folder(tmp_path / "failed", _records("L0", 3, 0.0, 0.25))
    for run in (passed, failed):
        write_report(run)
    for page in ("report.md", "report.html"):
        text = (passed / page).read_text()
        assert "L0: every training task on its training layout; L1: the training " \
               "instructions on changed layouts; L2: new wordings on the training layouts; " \
               "L3: both, new wordings on changed layouts." in text, page
        assert "None: every episode passed every stage." in text, page
        assert "None: every episode passed" not in (failed / page).read_text(), page
    assert "| Stage | Episodes | Most common reasons |" in (failed / "report.md").read_text()
    assert "| Stage |" not in (passed / "report.md").read_text()
    svg = ElementTree.fromstring((passed / "figures" / "levels.svg").read_text())
    parents = {child: parent for parent in svg.iter() for child in parent}
    legend = next(element for element in svg.iter() if element.get("id") == "legend_1")
    assert not parents[legend].get("id", "").startswith("axes_")  # the figure's, not a panel's
