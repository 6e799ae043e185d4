"""Reports read at a glance: tasks named by level and full instruction (unique, with the id
beside it), wide matrices in tasks.html only with upright headers in a scrolling box, and
completion told apart from doing as instructed."""

from __future__ import annotations

import html
import json
import re
from collections import Counter
from dataclasses import replace

from robofollow.eval.reports.report import write_report
from robofollow.eval.reports.report_data import report_data
from robofollow.eval.running.outcomes import DID, UNTRAINED
from tests.report_helpers import OPTIONS, fake_record

PLACE = ("Use your right arm to pick up the smaller blue object and place it in the {} bowl, "
         "then go home.")
ROUTE = ("Use your right arm to pick up the red slab, avoid passing over the {} slab, and place "
         "it on the blue label with the {} side facing front.")
INSTRUCTIONS = {  # task (label@layout/variant) -> its instruction
    "place_green@default/referents-1": PLACE.format("green"),
    "place_yellow@default/referents-2": PLACE.format("yellow"),
    "pickup@scene2_1": "Use your left arm to pick up the blue cylinder.",
    "pickup@scene2_3": "Use your left arm to pick up the blue cylinder.",
    "route_blue_long@default/routes-1": ROUTE.format("blue", "long"),
    "route_blue_short@default/routes-2": ROUTE.format("blue", "short"),
    "route_green_long@default/routes-3": ROUTE.format("green", "long"),
    "route_green_short@default/routes-4": ROUTE.format("green", "short"),
}
LAYOUTS = {"pickup@scene2_1": "scene2_1", "pickup@scene2_3": "scene2_3"}


def _records(matches: list[str | None], rounds: int = 1) -> list[dict]:
    """Every task of INSTRUCTIONS (level L2) for `rounds` rounds, the closest behaviours taken
    in turn from `matches`."""
    records = []
    for number, (task, text) in enumerate(INSTRUCTIONS.items()):
        for round_ in range(1, rounds + 1):
            match = matches[(number * rounds + round_) % len(matches)]
            record = fake_record(task, "L2", 0.0, 0.0, match == "instructed", match,
                             instruction=text, layout=LAYOUTS.get(task, "default"))
            records.append(dict(record, episode=f"{record['task']}#r{round_}"))
    return records


def _write(folder, records, options=OPTIONS):
    folder.mkdir()
    (folder / "run.json").write_text(json.dumps(options.to_json()))
    (folder / "episodes.jsonl").write_text("".join(json.dumps(r) + "\n" for r in records))
    return write_report(folder)


def test_tasks_are_named_by_level_and_full_instruction_and_told_apart():
    names = report_data("run", OPTIONS, _records(["instructed"]))["names"]
    by_task = {task.split("/", 2)[2]: name for task, name in names.items()}
    assert len(set(names.values())) == len(names)
    for task, name in by_task.items():  # never cut: "left of" / "right of" stay
        assert re.sub(r" (@\S+|\(\d+\))$", "", name) == f"L2 · {INSTRUCTIONS[task]}"
    # the same instruction on two layouts: the layout
    assert by_task["pickup@scene2_3"] == (
        "L2 · Use your left arm to pick up the blue cylinder. @scene2_3")
    assert by_task["place_green@default/referents-1"] == f"L2 · {PLACE.format('green')}"


def test_the_task_pages_give_the_full_instruction_and_the_id(tmp_path):
    markdown, _ = _write(tmp_path / "run", _records(["instructed"]))
    text, page = markdown.read_text(), (tmp_path / "run" / "tasks.html").read_text()
    for task, instruction in INSTRUCTIONS.items():
        assert f"| L2 · {instruction}" in text and f"| scene2/L2/{task} |" in text
        assert (f'<th class="task">L2 · {html.escape(instruction)}' in page
                and f'<small class="id">scene2/L2/{task}</small>' in page)


def test_runs_given_other_instructions_name_tasks_by_their_own_instruction(tmp_path):
    records = _records(["instructed"])
    for record in records:  # as the runner writes a shuffled run's records
        record["task_instruction"] = record["instruction"]
        record["instruction"] = "Use your right arm to push the red cube."
    shuffled = replace(OPTIONS, instruction_mode="shuffled")
    names = report_data("run", shuffled, records)["names"]
    assert names["scene2/L2/pickup@scene2_1"].startswith("L2 · Use your left arm to pick up")
    text = _write(tmp_path / "run", records, shuffled)[0].read_text()
    assert "push the red cube" not in text


def test_older_runs_given_other_instructions_name_their_tasks_by_id(tmp_path):
    records = _records(["instructed"])
    shuffled = replace(OPTIONS, instruction_mode="shuffled")
    names = report_data("run", shuffled, records)["names"]
    assert names["scene2/L2/pickup@scene2_1"] == "L2 · pickup@scene2_1"
    text = _write(tmp_path / "run", records, shuffled)[0].read_text()
    assert "Each task by its id" in text and "| L2 · pickup@scene2_1 |" in text
    assert "Use your left arm" not in text


def _html_matrix(page: str, scene: str) -> Counter:
    """A scene's HTML matrix as counts by (row name, column label)."""
    section = page.split(f"<h3>{scene}</h3>", 1)[1].split("</table>", 1)[0]
    columns = re.findall(r'<th class="behaviour"><span>(.*?)</span></th>', section)
    counts: Counter = Counter()
    for name, cells in re.findall(r'<th class="task" title="[^"]*">(.*?)</th>(.*?)</tr>',
                                  section):
        values = re.findall(r"<td[^>]*>(\d*)</td>", cells)
        counts.update({(html.unescape(name), html.unescape(label)): int(n)
                       for label, n in zip(columns, values, strict=True) if n})
    return counts


def test_a_wide_matrix_keeps_every_count_with_upright_headers_and_not_in_markdown(tmp_path):
    labels = [f"place_the_{colour}_cube_in_the_{bowl}_bowl_with_the_left_arm"
              for colour in ("red", "green", "blue", "white", "black", "orange", "pink")
              for bowl in ("near", "far", "middle")]
    records = _records(["instructed", None, *labels], rounds=10)
    markdown = _write(tmp_path / "run", records)[0].read_text()
    page = (tmp_path / "run" / "tasks.html").read_text()
    data = report_data("run", OPTIONS, records)
    assert len(data["matrices"]["scene2"]["columns"]) == 23
    assert '<div class="wide"><table class="matrix">' in page
    assert page.count('<th class="behaviour"><span>') == 23  # one header row, upright
    outcome = {"instructed": DID[0], None: UNTRAINED}
    assert _html_matrix(page, "scene2") == Counter(
        (data["names"][r["task"]], outcome.get(r["executed_behaviour"]["match"],
                                               r["executed_behaviour"]["match"]))
        for r in records)
    assert "matrix of every task is in tasks.html" in markdown
    assert "matrix" not in (tmp_path / "run" / "report.html").read_text()
    assert max(line.count("|") for line in markdown.splitlines()) <= 16  # no 23-column table


def test_completion_is_told_apart_from_doing_as_instructed(tmp_path):
    records = _records(["instructed", "pickup_left_cube"])
    records[0]["complete"] = True  # completed, closest to another training task
    markdown, html = _write(tmp_path / "run", records)
    text, page = markdown.read_text(), html.read_text()
    assert ("| Scene | Level | Completed: end state | Closest: as instructed | another training "
            "task | other branch | nothing moved | moved but touched nothing | handled objects "
            "in no trained way |") in text
    assert "| scene2 | L2 | 62.5 | 50.0 | 50.0 | 0.0 | 0.0 | 0.0 | 0.0 |" in text
    assert "An episode can be completed without being closest to the\ninstruction" in text
    assert "Closest behaviour to what the arms did</th>" in page
    assert "<caption>Completed (the instructed end state) is not the same as done as " \
           "instructed (the closest behaviour)</caption>" in page
