"""The README's task-author walk-through, step by step: copy the specs, add the README's layout
and task to Scene 2, list the layout in the L1 and L3 rules, compile; the summary says what
the README says, and the expert performs the new tasks in simulation."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from robofollow.audit.report import findings
from robofollow.benchmark.pipeline import compile_specs
from robofollow.benchmark.rounds import all_episodes
from robofollow.benchmark.summary import summary
from robofollow.eval.running.verify import run_expert_episodes
from robofollow.resources import builtin_specs
from tests.cli_helpers import run

README = Path(__file__).resolve().parent.parent / "README.md"
MARK = "<!-- walkthrough: scene2 -->"


def _snippet() -> str:
    text = README.read_text(encoding="utf-8")
    block = text[text.index(MARK) + len(MARK):].split("```", 2)[1]
    return block.partition("\n")[2]  # the lines after the opening fence


def _my_specs(tmp_path: Path) -> Path:
    """The README's steps: a copy of the specs with its layout and task in Scene 2, the layout
    listed in the L1 and L3 rules."""
    specs = tmp_path / "my-specs"
    shutil.copytree(builtin_specs(), specs)
    scene2 = specs / "scene2.rf"
    text = scene2.read_text(encoding="utf-8")
    end = text.rindex("}")
    text = text[:end] + _snippet() + text[end:]
    for level in ("L1", "L3"):
        text = text.replace(f"split {level} layouts=(scene2_1, scene2_2, scene2_3, scene2_4, "
                            "scene2_5, scene2_6)", f"split {level} layouts=(scene2_1, scene2_2, "
                            "scene2_3, scene2_4, scene2_5, scene2_6, scene2_7)")
    scene2.write_text(text, encoding="utf-8")
    return specs


def test_the_readme_walkthrough_compiles_as_described(tmp_path):
    specs = _my_specs(tmp_path)
    compiled = compile_specs(specs)
    text = summary(compiled)
    assert "RoboFollow: 4 scenes, 76 training tasks" in text
    assert "H(T|S) = 3.804 bits" in text
    assert findings(compiled.report) == 0 and not compiled.report["split_rules"]["warnings"]
    layouts = compiled.report["split_rules"]["layouts"]["scene2"]
    assert layouts["L1"]["scene2_7"] == 6 and layouts["L3"]["scene2_7"] == 6
    new = [t for t in compiled.splits.tasks
           if t.id == "scene2/L0/push_right_cube_to_blue_cylinder" or t.layout == "scene2_7"]
    assert len(new) == 13
    moved = {r.origin: r.reason for r in compiled.splits.rejected
             if r.layout == "scene2_7" and r.level == "L1" and "small_red_cube" in r.reason}
    assert len(moved) == 6 and all(reason.startswith("repertoire: ")
                                   and any(f"new {part}" in reason for part in (
                                       "pick location", "put location", "push start",
                                       "push end"))
                                   for reason in moved.values())
    assert "pick left small_red_cube: no training step moves alike; against the nearest, " \
           "pickup_blue_cylinder (pick left small_blue_cylinder on default), new pick location: " \
           "from the table at (-3.0, -22.0, 76.0) cm" in moved["pickup_right_cube"]

    ids = {t.id for t in new}
    episodes = [e for e in all_episodes(compiled) if e.task in ids and e.round == 1]
    results = run_expert_episodes(specs, episodes, workers=2, quiet=True)
    assert [r["episode"] for r in results if not r["full"]] == []


def test_the_readme_walkthrough_verifies_the_changed_scene_alone(tmp_path, capsys, monkeypatch):
    """`robofollow compile my-specs/ --out build/ --verify`, as the README says it: the expert
    is sent the changed scene's episodes only, as many as the README counts, with the time
    they take; `--verify-all` sends every scene's. (Whether the expert scores the new tasks
    in full: the test above, in simulation.)"""
    from robofollow.eval.running import verify

    command = "robofollow compile my-specs/ --out build/ --verify"
    readme = " ".join(README.read_text(encoding="utf-8").split())
    assert f"`{command}`" in readme
    _my_specs(tmp_path)
    sent: list = []

    def expert(specs, episodes, workers, quiet=False):
        sent.append([episode.id for episode in episodes])
        return [{"episode": episode.id, "full": True, "reasons": []} for episode in episodes]

    monkeypatch.setattr(verify, "run_expert_episodes", expert)
    monkeypatch.chdir(tmp_path)
    status, out, _ = run(capsys, *command.split()[1:], "--workers", "2")
    assert status == 0, out
    assert {episode.split("/")[0] for episode in sent[0]} == {"scene2"}
    count = len(sent[0])
    assert re.search(f"verifying scene2: the expert on {count} episodes \\(1 round of every test "
                     r"task\) in simulation, about (8\d|9\d) s on 2 workers", out), out
    assert f"round of each of its {count} test tasks, about a minute and a half" in readme
    with pytest.raises(SystemExit):  # (--verify and --verify-all are exclusive)
        run(capsys, *command.split()[1:], "--verify-all")
    status, out, _ = run(capsys, "compile", "my-specs/", "--out", "build/", "--verify-all",
                         "--workers", "2")
    assert status == 0 and {episode.split("/")[0] for episode in sent[1]} == {
        "scene1", "scene2", "scene3", "scene4"}
    assert f"`--verify-all` would run every scene's, {len(sent[1])} episodes" in readme
