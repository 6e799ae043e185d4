"""The 75 training labels and their 229 paraphrases (tests/data/training_instructions.json)."""

import json
from pathlib import Path

import pytest

from robofollow.compiler.language import lf
from robofollow.compiler.language.notation import notation
from robofollow.compiler.language.parser import parse

TASKS = json.loads((Path(__file__).parent / "data" / "training_instructions.json").read_text())
PARAPHRASES = [(task["label"], index, text) for task in TASKS
               for index, text in enumerate(task["paraphrases"])]

# Paraphrases whose words say something other than the label's first paraphrase:
# they name no arm ("Move the blue slab while avoiding ..."): their form has arm = null;
UNNAMED_ARM = {(task["label"], 2) for task in TASKS
               if task["scene"] == "scene3" and task["label"].startswith("l_")}
# they name the object by other words ("the red cylinder" for "the larger red object"): the
# forms differ in the object only, and grounding decides that both denote one object.
OTHER_DESCRIPTION = {(label, index) for label in ("pickup_red_cylinder", "pickup_blue_cylinder")
                     for index in (3, 4)}


def first_form(label: str) -> lf.Instruction:
    return parse(next(t for t in TASKS if t["label"] == label)["paraphrases"][0])


def test_the_data_is_complete():
    assert len(TASKS) == 75
    assert len(PARAPHRASES) == 229
    assert [sum(t["scene"] == f"scene{n}" for t in TASKS) for n in range(1, 5)] == [16, 16, 16, 27]


@pytest.mark.parametrize("label,index,text", PARAPHRASES, ids=lambda v: str(v)[:40])
def test_every_paraphrase_parses_to_its_labels_form(label, index, text):
    form, expected = parse(text), first_form(label)
    if (label, index) in UNNAMED_ARM:
        assert form.arm is None
        form = form.model_copy(update={"arm": expected.arm})
    if (label, index) in OTHER_DESCRIPTION:
        assert form.object != expected.object
        form = form.model_copy(update={"object": expected.object})
    assert lf.to_json(form) == lf.to_json(expected)


def test_exceptions_are_exactly_the_listed_ones():
    differing = {(label, index) for label, index, text in PARAPHRASES
                 if lf.to_json(parse(text)) != lf.to_json(first_form(label))}
    assert differing == UNNAMED_ARM | OTHER_DESCRIPTION
    assert len(differing) == 12


def test_other_descriptions_are_colour_and_shape():
    assert notation(parse("Use your left arm to pick up the red cylinder.")) == \
        "pick(left, cylinder[red])"
    assert notation(first_form("pickup_red_cylinder")) == "pick(left, object[red, larger])"


def test_labels_in_one_layout_have_distinct_forms():
    groups: dict[tuple[str, str], list[str]] = {}
    for task in TASKS:
        groups.setdefault((task["scene"], task["layout"]), []).append(
            lf.to_json(parse(task["paraphrases"][0])))
    assert sorted(len(g) for g in groups.values()) == [4, 7, 16, 16, 16, 16]
    for forms in groups.values():
        assert len(set(forms)) == len(forms)


def test_labels_share_a_form_only_when_their_words_are_identical():
    by_form: dict[str, set[str]] = {}
    for task in TASKS:
        by_form.setdefault(lf.to_json(parse(task["paraphrases"][0])), set()).add(
            task["paraphrases"][0])
    assert all(len(texts) == 1 for texts in by_form.values())
    # scene4_1 and scene4_2 reuse four instructions word for word
    assert len(by_form) == 71
