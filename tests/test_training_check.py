"""Training tasks ground to one behaviour each: the reference's, for the shipped benchmark."""

import json
from pathlib import Path

import pytest

from robofollow.compiler.authoring.spec_loader import load_spec
from robofollow.compiler.splits.training import check_training, describe
from robofollow.errors import SpecErrors
from tests.spec_helpers import edit, route_task, routes_with

SPECS = Path(__file__).resolve().parent.parent / "specs"
GOLDEN = json.loads((Path(__file__).parent / "data" / "training_behaviours.json").read_text())


@pytest.fixture(scope="module")
def behaviours():
    return check_training(load_spec(SPECS))


def test_every_training_task_grounds_to_the_reference_behaviour(behaviours):
    assert len(GOLDEN) == 75
    assert {label: describe(b) for label, b in behaviours.items()} == GOLDEN


def test_unnamed_arm_paraphrases_take_the_arm_the_others_name(behaviours):
    assert describe(behaviours["l_pick5_around2_to1_short_right"]) == \
        "place left blue_slab on green_label avoid red_slab yaw 90"


def test_conditionals_record_the_condition_and_the_other_branch(behaviours):
    chosen = behaviours["s41_if_blue_right_of_red_then_l_pick_else_r_stack"]
    assert (chosen.condition, chosen.branch) == (False, "otherwise")
    assert [(s.action, s.arm, s.source) for s in chosen.other] == [("pick", "left", "blue_sphere")]


def check(tmp_path, text):
    (tmp_path / "bad.rf").write_text(text)
    with pytest.raises(SpecErrors) as caught:
        check_training(load_spec(tmp_path))
    return caught.value.errors


TASK = '"Pick up the red cube with your left arm."'

# (replacement for the task's paraphrase and expect lines, code, line, column)
PROBLEMS = [
    ('"Pick up the green cube with your left arm."', "no-referent", 14, 9),
    ('"Pick up the cube with your left arm."', "ambiguous", 14, 9),
    (TASK + '\n        "Pick up the blue cube with your left arm."', "paraphrases-disagree", 15, 9),
    (TASK + '\n        "Pick up the red cube with your right arm."', "paraphrases-disagree", 15, 9),
    ('"Pick up the red cube."', "no-arm", 14, 9),
    ('"Pick up the bowl with your left arm."', "unsupported", 14, 9),
    ('"Pick up the red cube with your left arm."\n        expect pick left blue_cube',
     "expect-mismatch", 13, 10),
]


@pytest.mark.parametrize("paraphrases,code,line,column", PROBLEMS,
                         ids=[code for _, code, _, _ in PROBLEMS])
def test_task_problems_are_reported_at_the_paraphrase(tmp_path, paraphrases, code, line, column):
    text = edit(f"{TASK}\n        expect pick left red_cube", paraphrases)
    errors = check(tmp_path, text)
    assert [(e.code, e.line, e.column) for e in errors] == [(code, line, column)]
    assert errors[0].render().splitlines()[0].startswith(f"{errors[0].file}:{line}:{column}:")


def test_ambiguity_lists_the_candidates(tmp_path):
    errors = check(tmp_path, edit(TASK, '"Pick up the cube with your left arm."'))
    assert "red_cube" in errors[0].message and "blue_cube" in errors[0].message


def test_a_training_route_off_the_way_is_an_error(tmp_path):
    """scene3_3 puts the blue slab in the red slab's own column: passing over it turns back."""
    text = (SPECS / "scene3.rf").read_text().replace(" scene3_3,", "")  # (a training layout
    end = text.rindex("}")  # is no changed layout for the L1 and L3 rules to test on)
    (tmp_path / "scene3.rf").write_text(text[:end] + '''
    task backwards on scene3_3 {
        "Use your right arm to pick up the red slab, pass over the blue slab, and place it on the blue square label with the short side facing front."
    }
''' + text[end:])
    with pytest.raises(SpecErrors) as caught:
        check_training(load_spec(tmp_path))
    [error] = caught.value.errors
    assert (error.code, error.line) == ("degenerate-route", text[:end].count("\n") + 2)
    assert "'pass over blue_slab': blue_slab is not between red_slab and blue_label" in \
        error.message


def test_a_training_task_out_of_reach_is_an_error(tmp_path):
    text = (SPECS / "scene2.rf").read_text()
    end = text.rindex("}")
    (tmp_path / "scene2.rf").write_text(text[:end] + '''
    layout far from default { move small_red_cube to (0.40, 0.10) }
    task pick_far_cube on far {
        "Use your left arm to pick up the red cube."
    }
''' + text[end:])
    with pytest.raises(SpecErrors) as caught:
        check_training(load_spec(tmp_path))
    [error] = caught.value.errors
    assert error.code == "infeasible" and error.message.startswith(
        "the expert cannot do this: pre_grasp: the left arm would stretch 83.2 cm to (40.0, "
        "10.0, 84.0) cm with the jitter, beyond its 58.6 cm reach (and 3 more plan points)")


@pytest.mark.parametrize("layout, source, words, message", [
    # after the swap the red slab stands 7.8 cm off the carry: avoiding it asks for nothing
    ("swapped", "blue", "avoid passing over the red slab",
     ("'avoid red_slab': red_slab is 7.8 cm off the straight path from blue_slab to green_label; "
      "carried straight, blue_slab sweeps 2.8 cm to either side")),
    # the yellow slab stands on the red label: the carry passes over it while picking up
    ("base", "yellow", "pass over the red square label",
     "'pass over red_label': red_label lies in the footprint of yellow_slab"),
], ids=["avoid-off-the-path", "pass-over-at-pick-up"])
def test_a_training_route_that_asks_for_nothing_is_located(tmp_path, layout, source, words,
                                                            message):
    text = routes_with(route_task(layout, source, words))
    errors = check(tmp_path, text)
    line = text.index('"Use your left arm to pick up the ' + source)
    task_line = text[:line].count("\n")  # the line before the paraphrase's (1-based)
    assert [(e.code, e.line, e.column) for e in errors] == [("degenerate-route", task_line, 10)]
    assert errors[0].render().splitlines()[0].startswith(f"{errors[0].file}:{task_line}:10:")
    assert message in errors[0].message
