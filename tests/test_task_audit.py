"""Auditing task lists: every finding kind from a hand-written list, the compiled benchmark's
own tasks audited back with no finding, and the `robofollow audit --tasks` output."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from robofollow.audit.task_list import (
    FINDING_KINDS,
    ListedTask,
    audit_task_list,
    read_task_list,
    task_list,
)
from robofollow.benchmark.pipeline import compile_specs
from robofollow.cli import main
from robofollow.errors import RoboFollowError
from robofollow.resources import builtin_specs
from tests.sim_helpers import benchmark
from tests.spec_helpers import ROUTES


def _task(task_id: str, scene: str, level: str, layout: str, instruction: str,
          expect: dict | None = None) -> dict:
    return {"id": task_id, "scene": scene, "level": level, "layout": layout,
            "instruction": instruction, **({"expect": expect} if expect else {})}


LEFT_BOWL = "Use your right arm to place the blue cylinder in the leftmost bowl."
TASKS = [
    _task("typo", "scene2", "L2", "default", "Use your left arm to pik up the red cylinder."),
    _task("nothing", "scene2", "L2", "default", "Use your left arm to pick up the purple cube."),
    _task("two-cubes", "scene2", "L2", "default", "Use your left arm to pick up the cube."),
    _task("jitter", "scene1", "L2", "default",
          "Use your left arm to pick up the object to the right of the red sphere."),
    # the default layout's left bowl is green; scene2_5 swaps the bowls
    _task("swapped", "scene2", "L3", "scene2_5", LEFT_BOWL, {"steps": [
        {"action": "place", "arm": "right", "source": "small_blue_cylinder", "relation": "in",
         "target": "green_bowl"}]}),
    _task("other-arm", "scene2", "L2", "default",
          "Use your right arm to pick up the red cylinder."),
    _task("copied", "scene2", "L2", "default", "Use your left arm to pick up the red cylinder."),
    _task("new-layout-l2", "scene2", "L2", "scene2_1",
          "Use your left arm to grab the blue cylinder."),
    _task("rephrased-l1", "scene2", "L1", "scene2_1",
          "Use your left arm to grab the blue cylinder."),
    _task("where", "scene2", "L2", "nowhere", "Use your left arm to grab the blue cylinder."),
    _task("fine", "scene2", "L2", "default", LEFT_BOWL, {"steps": [
        {"action": "place", "arm": "right", "source": "small_blue_cylinder", "target":
         "green_bowl"}]}),
    _task("twice", "scene2", "L2", "default", LEFT_BOWL),
    # the added layout same_look swaps two identical yellow blocks: nothing visible changes
    _task("look-alike", "scene1", "L1", "same_look",
          "Use your left arm to pick up the block to the left of the green ball."),
    # scene3_3 puts the blue slab in the red slab's own column: passing over it turns back
    _task("backwards", "scene3", "L1", "scene3_3",
          "Use your right arm to pick up the red slab, pass over the blue slab, and place it on "
          "the blue square label with the short side facing front."),
    # the added layout far puts the red cube beyond either arm's reach
    _task("far", "scene2", "L1", "far", "Use your left arm to pick up the rightmost cube."),
    _task("new-pick", "scene1", "L1", "scene1_1",
          "Use your right arm to pick up the block in front of the red cylinder and place it "
          "behind the green ball."),
    _task("new-put", "scene1", "L1", "scene1_1",
          "Use your right arm to pick up the block to the right of the red ball and place it "
          "behind the red cylinder."),
    _task("new-object", "scene2", "L1", "scene2_2",
          "Pick up the smaller blue object using your left arm."),
    # the blue cube is the larger one, and the yellow bowl the larger bowl
    _task("misordered", "scene2", "L2", "default",
          "Use your left arm to place the blue cylinder on the blue smaller cube."),
    _task("clause", "scene2", "L2", "default",
          "Use your left arm to pick up the blue cube that is rightmost."),
    _task("one-bowl", "scene2", "L2", "default", "Use your right arm to pick up the rightmost "
          "cube and place it in the smaller yellow bowl."),
    _task("new-pair", "scene4", "L1", "scene4_4",
          "First use your left arm to pick up the red sphere, then use your right arm to pick up "
          "the green cylinder."),
]
EXTRA_LAYOUTS = {
    "scene1": "layout same_look from default { swap yellow_block_1 yellow_block_3 }",
    "scene2": "layout far from default { move small_red_cube to (0.45, 0.2) }",
}


def extended_specs(folder: Path) -> Path:
    """The built-in specs with EXTRA_LAYOUTS added to their scenes."""
    folder.mkdir()
    for source in sorted(builtin_specs().glob("*.rf")):
        text = source.read_text()
        extra = EXTRA_LAYOUTS.get(source.stem)
        if extra:
            at = text.index("    split L0")
            text = text[:at] + f"    {extra}\n" + text[at:]
        (folder / source.name).write_text(text)
    return folder


@pytest.fixture(scope="module")
def findings(tmp_path_factory) -> dict[str, list[tuple[str, str]]]:
    compiled = compile_specs(extended_specs(tmp_path_factory.mktemp("audit") / "specs"))
    listed = [ListedTask(**task) for task in TASKS]
    result = audit_task_list(compiled.spec, compiled.training, listed)
    assert result["checked"] == len(TASKS)
    grouped: dict[str, list] = {task["id"]: [] for task in TASKS}
    for finding in result["findings"]:
        grouped[finding["id"]].append((finding["kind"], finding["message"]))
    return grouped


def test_every_kind_of_finding_is_reported(findings):
    kinds = {kind for items in findings.values() for kind, _ in items}
    assert kinds == set(FINDING_KINDS)


@pytest.mark.parametrize("task_id, kind, words", [
    ("typo", "parse", "column 22: unknown word 'pik'"),
    ("nothing", "no-referent", "the layout's cubes: large_blue_cube, small_red_cube"),
    ("two-cubes", "ambiguous", "large_blue_cube at (-14.0, -13.0) cm"),
    ("jitter", "ambiguous", "at jitter extreme 5: object[right_of(sphere[red])]: green_sphere "
                            "stands 43° off the right_of direction of red_sphere, too near the "
                            "45° edge to tell"),
    ("swapped", "expectation", "the words select target yellow_bowl; the expectation says "
                               "green_bowl"),
    ("other-arm", "repertoire", "pick right large_red_cylinder: no training step moves alike; "
                                "against the nearest, pickup_red_cylinder (pick left "
                                "large_red_cylinder on default), new arm: the right arm "
                                "(trained: the left arm)"),
    ("copied", "leakage", "its form is a training form"),
    ("new-layout-l2", "level", "an L2 task is on a training layout"),
    ("rephrased-l1", "level", "an L1 task's instruction is a training instruction"),
    ("where", "invalid", "scene2 has no layout 'nowhere'"),
    ("twice", "duplicate", "it repeats fine: the same meaning on the same layout"),
    ("look-alike", "level", "an L1 task is on a layout that looks different from every "
                            "training layout, but same_look looks the same as default"),
    ("backwards", "route", "'pass over blue_slab': blue_slab is not between red_slab and "
                           "blue_label"),
    ("far", "infeasible", "the left arm would stretch"),
    ("new-pick", "repertoire", "new pick location: from the table at (-14.0, -18.0, 76.0) cm "
                               "(trained: from the table at (-2.0, -4.0, 76.0) cm)"),
    ("new-put", "repertoire", "new put location: to (-14.0, 4.5, 76.1) cm (trained: to "
                              "(10.0, 4.5, 76.1) cm)"),
    ("new-object", "repertoire", "new object: 4.0 x 4.0 x 5.0 cm, upright (trained: 6.0 x 6.0 "
                                 "x 6.0 cm, upright)"),
    ("misordered", "wording", "order: 'blue smaller' puts a colour before a size word"),
    ("misordered", "wording", "vacuous: 'smaller' in 'cube[blue, smaller]' compares 1 body "
                              "(large_blue_cube)"),
    ("clause", "wording", "clause: 'cube[blue, rightmost]' is scored as large_blue_cube, but "
                          "the rightmost cube is small_red_cube"),
    ("one-bowl", "wording", "vacuous: 'smaller' in 'bowl[yellow, smaller]' compares 1 body"),
    ("new-pair", "repertoire", "every step is trained, but no training task performs them "
                               "together in this order"),
])
def test_each_task_gets_its_finding_with_an_explanation(findings, task_id, kind, words):
    assert [k for k, _ in findings[task_id]].count(kind) >= 1
    assert any(words in message for k, message in findings[task_id] if k == kind), \
        findings[task_id]


def test_findings_stay_with_their_cause(findings):
    assert [k for k, _ in findings["swapped"]] == ["expectation"]
    assert [k for k, _ in findings["jitter"]] == ["ambiguous"]  # fine at the nominal positions
    assert [k for k, _ in findings["other-arm"]] == ["repertoire"]
    assert findings["fine"] == []


def test_the_compiled_benchmark_audits_back_without_findings():
    compiled = benchmark()
    exported = task_list(compiled.splits)
    assert len(exported) == len(compiled.splits.tasks)
    result = audit_task_list(compiled.spec, compiled.training,
                             [ListedTask(**json.loads(json.dumps(t))) for t in exported])
    assert result == {"checked": len(exported), "findings": []}


def test_the_cli_exports_audits_and_groups_findings(tmp_path, capsys):
    specs = str(builtin_specs())
    exported = tmp_path / "tasks.jsonl"
    assert main(["audit", specs, "--export-tasks", str(exported), "--tasks",
                 str(exported)]) == 0
    count = len(exported.read_text().splitlines())
    assert count > 600 and f"{count} tasks checked, no findings" in capsys.readouterr().out
    listed = tmp_path / "mine.jsonl"
    listed.write_text("".join(json.dumps(t) + "\n" for t in TASKS[:3]))
    assert main(["audit", specs, "--tasks", str(listed)]) == 1
    text = capsys.readouterr().out
    assert "3 tasks checked, 3 findings" in text and "ambiguous: 1\n  two-cubes: cube" in text
    assert main(["audit", specs, "--tasks", str(listed), "--json"]) == 1
    report = json.loads(capsys.readouterr().out)
    assert report["checked"] == 3 and [f["kind"] for f in report["findings"]] == [
        "parse", "no-referent", "ambiguous"]
    assert "scene_entropy_bits" in report  # the audit object, extended


@pytest.mark.parametrize("line, message", [
    ('{"id": "a", "scene": "scene2"}', ":2: level: Field required; layout: Field required"),
    ("{oops", ":2: line: Invalid JSON"),
    (json.dumps(TASKS[0]), ":2: id 'typo' is also on line 1"),
])
def test_bad_task_list_lines_are_named(tmp_path, line, message):
    path = tmp_path / "bad.jsonl"
    path.write_text(json.dumps(TASKS[0]) + "\n" + line + "\n")
    with pytest.raises(Exception, match=message):
        read_task_list(path)


def test_a_task_list_that_is_not_utf8_is_named_at_its_byte(tmp_path):
    path = tmp_path / "bad.jsonl"
    path.write_bytes(json.dumps(TASKS[0]).encode() + b'\n{"id": "\xff"}\n')
    with pytest.raises(RoboFollowError, match=r"bad.jsonl:2:9: not UTF-8 text \(byte 0xff\)"):
        read_task_list(path)


def _route_task(task_id: str, layout: str, source: str, words: str) -> dict:
    return _task(task_id, "routes", "L1", layout,
                 f"Use your left arm to pick up the {source} slab, {words}, and place it on the "
                 "green square label.")


def test_routes_that_ask_for_nothing_are_route_findings(tmp_path, capsys):
    """A listed 'avoid X' whose X a straight carry never passes over (after a swap), and a
    'pass over W' that the carry passes over at pick-up or set-down, are `route` findings."""
    specs = tmp_path / "specs"
    specs.mkdir()
    (specs / "routes.rf").write_text(ROUTES)
    listed = [
        _route_task("sound", "swapped", "blue", "avoid passing over the green slab"),
        _route_task("off-path", "swapped", "blue", "avoid passing over the red slab"),
        _route_task("pick-up", "sources_swapped", "blue", "pass over the red square label"),
        _route_task("set-down", "set_down", "blue", "pass over the blue square label"),
    ]
    path = tmp_path / "tasks.jsonl"
    path.write_text("".join(json.dumps(t) + "\n" for t in listed))
    assert main(["audit", str(specs), "--tasks", str(path), "--json"]) == 1
    report = json.loads(capsys.readouterr().out)
    routes = {f["id"]: f["message"] for f in report["findings"] if f["kind"] == "route"}
    assert sorted(routes) == ["off-path", "pick-up", "set-down"]
    assert routes["off-path"].startswith(
        "'avoid red_slab': red_slab is 7.8 cm off the straight path from blue_slab to "
        "green_label; carried straight, blue_slab sweeps 2.8 cm to either side and red_slab "
        "reaches 2.8 cm towards the path, so a straight carry clears it by 2.2 cm")
    assert "lies in the footprint of blue_slab" in routes["pick-up"]
    assert "while picking up" in routes["pick-up"]
    assert "lies in the footprint of green_label" in routes["set-down"]
    assert "while setting down" in routes["set-down"]
    compiled = compile_specs(specs)
    result = audit_task_list(compiled.spec, compiled.training,
                             [ListedTask(**t) for t in listed])
    assert [f["id"] for f in result["findings"] if f["kind"] == "route"] == [
        "off-path", "pick-up", "set-down"]
