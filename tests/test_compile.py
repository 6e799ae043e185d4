"""`robofollow compile` and `robofollow audit` on the shipped specs and on bad specs."""

import json
import subprocess
from pathlib import Path

import pytest

from robofollow import cli
from robofollow.audit.report import findings
from robofollow.audit.task_list import ListedTask, audit_task_list, task_list
from robofollow.benchmark.pipeline import compile_specs
from robofollow.resources import builtin_specs
from tests.spec_helpers import edit

SPECS = Path(__file__).resolve().parent.parent / "specs"
# the upstream benchmark's tasks per level, but Scene 1's L3 (see tests/test_splits.py)
TARGETS = {"scene1": [16, 8, 16, 17], "scene2": [16, 24, 68, 24], "scene3": [16, 40, 64, 96],
           "scene4": [27, 14, 25, 24]}


@pytest.fixture(scope="module")
def compiled(tmp_path_factory):
    out = tmp_path_factory.mktemp("compiled")
    result = subprocess.run(["robofollow", "compile", str(SPECS), "--out", str(out)],
                            capture_output=True, text=True)
    return out, result


def test_compile_succeeds_with_a_clean_audit(compiled):
    out, result = compiled
    assert result.returncode == 0, result.stderr
    assert "H(T|S) = 3.782 bits" in result.stdout
    report = json.loads((out / "audit.json").read_text())
    assert round(report["scene_entropy_bits"], 3) == 3.782
    assert report["leakage"] == report["repertoire_violations"] == report["ambiguities"] == []
    for scene, targets in TARGETS.items():
        counts = [report["counts"][scene][level] for level in ("L0", "L1", "L2", "L3")]
        assert all(c >= t for c, t in zip(counts, targets, strict=True)), (scene, counts)
    assert report["rejected"] == sum(1 for _ in open(out / "rejected.jsonl"))


def test_episode_files_hold_rounds_with_seeds_and_hashes(compiled):
    out, _ = compiled
    lines = (out / "episodes" / "scene2_L0.jsonl").read_text().splitlines()
    assert len(lines) == 16 * 10
    first = json.loads(lines[0])
    assert {"episode", "task", "scene", "level", "layout", "instruction", "lf", "behaviour",
            "seed", "round", "hash"} <= set(first)
    assert first["instruction"] == "Use your left arm to pick up the larger red object."
    tasks = [json.loads(x) for x in (out / "tasks" / "scene2_L0.jsonl").read_text().splitlines()]
    assert [n["weight"] for n in tasks[0]["goal"]["nodes"]] == [0.8, 0.2]
    assert [p["name"] for p in tasks[0]["plan"]] == ["pre_grasp", "grasp", "close", "lift",
                                                     "home"]


def test_two_compiles_are_byte_identical(compiled, tmp_path):
    out, _ = compiled
    assert cli.main(["compile", str(SPECS), "--out", str(tmp_path)]) == 0
    for path in sorted(out.rglob("*")):
        if path.is_file():
            assert (tmp_path / path.relative_to(out)).read_bytes() == path.read_bytes(), path


def test_audit_json_has_the_documented_keys(capsys):
    assert cli.main(["audit", str(SPECS), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert {"scene_entropy_bits", "groups", "counts", "leakage", "repertoire_violations",
            "ambiguities", "rejected", "blind_best"} <= set(report)
    assert isinstance(report["scene_entropy_bits"], float)
    assert set(report["blind_best"]) == set(report["counts"])
    assert all({"layout", "tasks"} <= set(g) for g in report["groups"])


def test_bad_specs_are_reported_with_positions_and_exit_1(tmp_path, capsys):
    bad = edit("blue_cube at p1", "green_cube at p1").replace("color=blue", "color=navy")
    (tmp_path / "bad.rf").write_text(bad)
    assert cli.main(["compile", str(tmp_path), "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err
    assert f"{tmp_path / 'bad.rf'}:4:43: error[bad-value]" in err
    assert f"{tmp_path / 'bad.rf'}:9:9: error[unknown-object]" in err
    assert err.rstrip().endswith("2 errors in the specs")
    assert not (tmp_path / "out").exists()


def test_injected_leaks_are_caught():
    from robofollow.audit.splits import task_findings
    from robofollow.benchmark.pipeline import compile_specs

    def leakage(spec, splits):
        return task_findings(spec, compiled.training, splits)["leakage"]

    compiled = compile_specs(SPECS)
    spec, splits = compiled.spec, compiled.splits
    training = spec.scenes["scene1"].tasks[0]
    l2 = splits.of("scene1", "L2")[0]
    copied = l2.model_copy(update={"form": training.forms[0]})
    named = l2.model_copy(update={"id": l2.id + "x",
                                  "instruction": f"Pick up {training.label} now."})
    tampered = splits.model_copy(update={"tasks": splits.tasks + (copied, named)})
    found = {(f["task"], f["finding"].split(" ")[1]) for f in leakage(spec, tampered)}
    assert (copied.id, "form") in found
    assert (named.id, "instruction") in found
    assert leakage(spec, splits) == []


@pytest.mark.parametrize("spec_file", sorted(builtin_specs().glob("*.rf")), ids=lambda p: p.stem)
def test_every_shipped_scene_compiles_alone_without_findings_and_audits_back(spec_file):
    compiled = compile_specs(spec_file)
    assert findings(compiled.report) == 0
    assert compiled.report["split_rules"]["warnings"] == []
    exported = [ListedTask(**t) for t in task_list(compiled.splits)]
    assert audit_task_list(compiled.spec, compiled.training, exported)["findings"] == []
