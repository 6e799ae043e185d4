"""Loading specs: the shipped benchmark, and malformed specs reported at file:line:col."""

import json
from pathlib import Path

import pytest

from robofollow.benchmark.pipeline import compile_specs
from robofollow.compiler.authoring.spec_loader import load_spec
from robofollow.errors import SpecErrors
from tests.spec_helpers import VALID, edit

SPECS = Path(__file__).resolve().parent.parent / "specs"
TRAINING = json.loads((Path(__file__).parent / "data" / "training_instructions.json").read_text())


@pytest.fixture(scope="module")
def spec():
    return load_spec(SPECS)


def test_the_benchmark_is_complete(spec):
    assert sorted(spec.scenes) == ["scene1", "scene2", "scene3", "scene4"]
    assert [len(s.tasks) for s in spec.scenes.values()] == [16, 16, 16, 27]
    assert sum(len(t.paraphrases) for t in spec.tasks) == 229
    assert [len(s.layouts) for s in spec.scenes.values()] == [4, 7, 5, 8]
    assert spec.scenes["scene4"].training_layouts == ("scene4_1", "scene4_2", "scene4_3")


def test_specs_carry_the_training_paraphrases_verbatim(spec):
    written = {t.label: (t.scene, t.layout, list(t.paraphrases)) for t in spec.tasks}
    assert written == {t["label"]: (t["scene"], t["layout"], t["paraphrases"]) for t in TRAINING}


def test_layout_operations_resolve_to_poses(spec):
    scene = spec.scenes["scene4"]
    first, third = scene.layouts["scene4_1"].placed, scene.layouts["scene4_3"].placed
    assert (first["green_cylinder"].support, first["green_cylinder"].relation) == ("blue_cube", "on")
    assert first["red_cube"].relation == "in"
    assert (third["blue_cube"].x, third["blue_cube"].support) == (-0.02, "yellow_cylinder")
    assert (third["green_cylinder"].x, third["green_cylinder"].relation) == (0.10, "table")
    assert "red_cube" not in third
    top = third["blue_cube"].z - 0.024
    assert top == pytest.approx(third["yellow_cylinder"].z + 0.025)
    swapped = spec.scenes["scene1"].layouts["scene1_1"].placed
    assert (swapped["red_sphere"].x, swapped["red_sphere"].y) == (-0.02, -0.18)
    assert (swapped["red_cylinder"].x, swapped["green_sphere"].x) == (-0.14, 0.10)


def test_the_digest_follows_the_text(tmp_path):
    (tmp_path / "a.rf").write_text(VALID)
    first = load_spec(tmp_path).digest
    (tmp_path / "a.rf").write_text(VALID + "\n# a comment\n")
    assert load_spec(tmp_path).digest != first


def errors_of(tmp_path, text, name="bad.rf"):
    (tmp_path / name).write_text(text)
    with pytest.raises(SpecErrors) as caught:
        load_spec(tmp_path)
    return caught.value.errors


# (spec text, error code, line, column)
MALFORMED = [
    (edit("blue_cube at p1", "green_cube at p1"), "unknown-object", 9, 9),
    (edit("color=blue rgb=(0, 0, 1)", "color=blue rgb=(1, 0, 0)"), "colour-mismatch", 4, 12),
    (edit("red_cube at (-0.1, 0.0)", "red_cube at (0.3, 0.3)"), "off-table", 8, 9),
    (edit("red_cube at (-0.1, 0.0)", "red_cube at (0.08, 0.01)"), "overlap", 9, 9),
    (edit("red_cube at (-0.1, 0.0)", "red_cube at (0.05, 0.0)"), "overlap", 9, 9),
    (edit("blue_cube at p1", "blue_cube at p9"), "unknown-point", 9, 22),
    (edit("swap red_cube blue_cube", "swap red_cube red_cube"), "swap-self", 12, 46),
    (edit("swap red_cube blue_cube", "swap red_cube bowl_two"), "unknown-object", 12, 46),
    (edit("from base", "from bass"), "undefined-layout", 12, 25),
    (edit("task pick_red on base", "task pick_red on nowhere"), "undefined-layout", 13, 22),
    (edit("layout swapped from base { swap red_cube blue_cube }",
          "layout swapped from other { swap red_cube blue_cube }\n"
          "    layout other from swapped { remove red_cube }"), "layout-cycle", 12, 12),
    (edit("blue_cube at p1", "blue_cube at (-0.09, 0.0)"), "overlap", 9, 9),
    (edit("blue_cube at p1", "blue_cube on red_cube\n        red_cube on blue_cube"),
     "support-cycle", 10, 9),
    (edit("blue_cube at p1", "blue_cube in red_cube"), "not-a-container", 9, 22),
    (edit("swap red_cube blue_cube", "remove red_cube\n        move red_cube to p1"),
     "not-in-layout", 13, 14),
    (edit("    layout swapped", "    layout swapped from base { blue_cube on red_cube  remove red_cube }\n"
          "    layout other"), "support-removed", 12, 62),
    (edit("layout swapped", "layout base"), "duplicate-layout", 12, 12),
    (edit("task pick_red on base {", "task pick_red on base {\n        \"Pick up the red cube.\"\n    }\n"
          "    task pick_red on base {"), "duplicate-label", 16, 10),
    (edit("object blue_cube cube", "object red_cube cube"), "duplicate-object", 4, 12),
    (edit("point p1 (0.1, 0.0)", "point p1 (0.1, 0.0)\n    point p1 (0.2, 0.0)"),
     "duplicate-point", 3, 11),
    (edit("split L1", "split L0 rounds=10\n    split L0"), "duplicate-split", 18, 11),
    (edit("cube half=0.02 color=red", "cube half=0.02 colour=red"), "unknown-attribute", 3, 36),
    (edit("cube half=0.02 color=red", "cube color=red"), "missing-attribute", 3, 12),
    (edit("cube half=0.02 color=red", "cube half=0.02 color=crimson"), "bad-value", 3, 42),
    (edit("rgb=(1, 0, 0)", "rgb=(1, 0)"), "bad-value", 3, 46),
    (edit("rgb=(1, 0, 0)", "rgb=(2, 0, 0)"), "bad-value", 3, 51),
    (edit("half=0.02 color=red", "half=-0.02 color=red"), "bad-value", 3, 31),
    (edit("mass=0.2 friction=0.1\n    object blue", "mass=0 friction=0.1\n    object blue"),
     "bad-value", 3, 65),
    (edit("object red_cube cube", "object red_cube pyramid"), "unknown-kind", 3, 21),
    (edit("jitter * x=", "jitter purple_cube x="), "unknown-object", 6, 12),
    (edit("jitter * x=[-0.01, 0.01]", "jitter * x=[0.01, -0.01]"), "bad-value", 6, 14),
    (edit("    jitter", "    set gravity = 9.8\n    jitter"), "unknown-setting", 6, 9),
    (edit("split L1 layouts=(swapped)", "split L1 layouts=(missing)"), "undefined-layout", 17, 23),
    (edit("split L1 layouts=(swapped)", "split L1 layouts=(swapped) wordings=(rhymes)"),
     "unknown-wording", 17, 42),
    (edit("rounds=10 seed=42", "rounds=0 seed=42"), "bad-value", 17, 39),
    (edit("layouts=(swapped) rounds", "layouts=(swapped) motion=moevd rounds"), "bad-value",
     17, 39),
    (edit("layouts=(swapped) rounds", "layouts=(swapped) motion=(moved) rounds"), "bad-value",
     17, 32),
    (edit("split L1", "split L0 motion=moved\n    split L1"), "unknown-attribute", 17, 14),
    (edit("expect pick left red_cube", "expect pick middle red_cube"), "bad-value", 15, 21),
    (edit("expect pick left red_cube", "expect pick left teal_cube"), "unknown-object", 15, 26),
    (edit("Pick up the red cube with", "Pick up the red cubee with"), "instruction-unknown_word",
     14, 26),
    (edit("Pick up the red cube with", "Pick up the the red cube with"), "instruction-ungrammatical",
     14, 22),
    (edit("Pick up the red cube with your left arm.", "Pick it up."),
     "instruction-unsupported", 14, 15),
    (edit("layout base {", "layout base {{"), "syntax", 7, 18),
    (edit("task pick_red on base {", "task pick_red base {"), "syntax", 13, 19),
    (edit("half=0.02 color=red", "half=0.02 color=red %"), "syntax", 3, 46),
    (VALID.rstrip().rstrip("}"), "syntax", 17, 49),
    (edit('scene demo "Demo"', "scene demo"), "syntax", 1, 12),
]


def test_there_are_at_least_thirty_malformed_specs():
    assert len(MALFORMED) >= 30


@pytest.mark.parametrize("text,code,line,column", MALFORMED,
                         ids=[f"{i}-{code}" for i, (_, code, _, _) in enumerate(MALFORMED)])
def test_malformed_spec_is_reported_at_its_position(tmp_path, text, code, line, column):
    errors = errors_of(tmp_path, text)
    assert (errors[0].code, errors[0].line, errors[0].column) == (code, line, column)
    assert errors[0].file.endswith("bad.rf")
    rendered = errors[0].render().splitlines()
    assert rendered[0].startswith(f"{errors[0].file}:{line}:{column}: error[{code}]: ")


def test_a_split_rule_may_ask_for_moved_tasks_only(tmp_path):
    (tmp_path / "a.rf").write_text(edit("layouts=(swapped) rounds",
                                        "layouts=(swapped) motion=moved rounds"))
    splits = load_spec(tmp_path).scenes["demo"].splits
    assert splits["L1"].motion == "moved"
    (tmp_path / "a.rf").write_text(VALID)
    assert load_spec(tmp_path).scenes["demo"].splits["L1"].motion == "any"


def test_a_misspelt_motion_is_located_with_a_suggestion(tmp_path):
    [error] = errors_of(tmp_path, edit("layouts=(swapped) rounds",
                                       "layouts=(swapped) motion=moevd rounds"))
    assert "unknown motion moevd; did you mean 'moved'?" in error.message
    assert error.render().splitlines()[0].endswith("(known: any | moved: every task, or only "
                                                   "those whose expert motion differs from the "
                                                   "training task's)")
    [error] = errors_of(tmp_path, edit("split L1", "split L2 motion=moved\n    split L1"))
    assert error.message == ("motion applies to L1 and L3 (the levels on changed layouts), "
                             "not to L2")


def test_every_problem_is_reported_at_once(tmp_path):
    text = edit("blue_cube at p1", "green_cube at p1").replace("color=blue", "color=navy")
    (tmp_path / "good.rf").write_text(VALID.replace("demo", "other").replace("pick_red", "x"))
    errors = errors_of(tmp_path, text)
    assert [e.code for e in errors] == ["bad-value", "unknown-object"]
    rendered = SpecErrors(errors).render()
    assert rendered.endswith("2 errors in the specs")
    assert "\n      object blue_cube cube half=0.02 color=navy" in rendered


def test_no_spec_files(tmp_path):
    assert [e.code for e in errors_of(tmp_path, "", name="empty.txt")] == ["no-specs"]


ONE_REPORT_A = """\
scene a "errors in one report" {
    object red_cube  cube half=0.02 color=violet rgb=(1, 0, 0) mass=0.2 friction=0.5
    object blue_cube cube half=0.02 color=blue rgb=(0, 0, 1) mass=0.2 friction=0.5
    object green_ball sphere radius=0.02 color=green rgb=(0, 1, 0) mass=0.2 friction=0.5
    layout base {
        red_cube  at (-0.08, -0.10)
        blue_cube at (0.08, -0.10)
    }
    layout other {
        blue_cube at (0.08, -0.10)
        green_ball at (-0.08, -0.10)
    }
    task pick_red on base {
        "Use your left arm to pick up the red cube."
        expect pick left red_cube
    }
    task pick_yellow on other {
        "Use your left arm to pick up the yellow cube."
    }
    task shared on other {
        "Use your right arm to pick up the blue cube."
    }
}
"""
ONE_REPORT_B = """\
scene b "another file" {
    object blue_cube cube half=0.02 color=blue rgb=(0, 0, 1) mass=0.2 friction=0.5
    layout base {
        blue_cube at (0.08, -0.10)
    }
    task shared on base {
        "Use your right arm to pick up the blue cube."
    }
}
"""


def test_every_error_of_a_run_in_one_report_without_cascades(tmp_path):
    """A bad attribute, a grounding error and a label defined in two files, all at once; the
    body with the bad colour is kept, so its name still resolves in `expect`, and the task on
    its layout is not checked (its error would only repeat the colour's)."""
    (tmp_path / "a.rf").write_text(ONE_REPORT_A)
    (tmp_path / "b.rf").write_text(ONE_REPORT_B)
    with pytest.raises(SpecErrors) as caught:
        compile_specs([tmp_path / "a.rf", tmp_path / "b.rf"])
    found = [(e.code, e.line, e.message) for e in caught.value.errors]
    assert [(code, line) for code, line, _ in found] == [
        ("bad-value", 2), ("duplicate-label", 6), ("no-referent", 18)]
    assert f"task shared is also defined at {tmp_path / 'a.rf'}:20:10" in found[1][2]
    assert caught.value.errors[1].file == str(tmp_path / "b.rf")
    assert not any("no object named" in message for _, _, message in found)
