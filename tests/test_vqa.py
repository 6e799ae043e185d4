"""The VQA probe: the paper's QA-20 answered on Scene 2's default layout, generated questions
that are all uniquely answerable, the free-text scorer, and the `robofollow vqa` commands."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robofollow.cli import main
from robofollow.compiler.language import lf
from robofollow.compiler.scene.grounding import Grounder
from robofollow.compiler.scene.world import (
    DIRECTIONS,
    EXTREME_MARGIN,
    World,
    sample_offsets,
)
from robofollow.resources import builtin_specs
from robofollow.vqa.paper import QA20, answer_all
from robofollow.vqa.questions import (
    RELATION_WORDS,
    Ask,
    questions,
    unique_answer,
)
from robofollow.vqa.score import score
from tests.sim_helpers import benchmark

SCENES = benchmark().spec.scenes
DEFAULT = World(SCENES["scene2"], "default")

QA20_ANSWERS = {
    1: "the red cylinder", 2: "yellow", 3: "green", 4: "red", 5: "red", 6: "blue",
    7: "the yellow bowl",
    8: "the red cylinder is on the left and the red cube is on the right",
    9: "the blue cylinder", 10: "blue",
    11: "the red cylinder is on the left and the red cube is on the right",
    12: "red", 13: "red",
    14: "the green bowl is on the left and the yellow bowl is on the right",
    15: "the red cube", 16: "blue", 17: "red", 18: "blue", 19: "green", 20: "green"}
# two candidates in the relation's cone, neither squarely there: the nearer answers
NEAREST = {20}


def test_the_paper_questions_are_answered_on_the_default_scene2_layout():
    answered = answer_all(DEFAULT)
    assert [q.question for q, _ in answered] == [text for text, _ in QA20]
    for number, (question, note) in enumerate(answered, start=1):
        assert question.answer == QA20_ANSWERS[number], (number, question.question)
        assert (note is not None) == (number in NEAREST), (number, note)
    assert "green_bowl, yellow_bowl" in answered[19][1]


NOUN = r"(square label|\w+)"


def _kind(words: str) -> str:
    return "label" if words == "square label" else words


def _landmark(world: World, words: str) -> str:
    color, noun = words.split(" ", 1)
    noun = _kind(noun)
    [body] = [b for b, spec in world.bodies.items() if spec.color == color and spec.kind == noun]
    return body


PHRASES = "|".join(sorted(RELATION_WORDS.values(), key=len, reverse=True))
RELATED = re.compile(rf"(?:the color of the|is the|Describe the) {NOUN} ({PHRASES}) the "
                     rf"(\w+ {NOUN})")


def _squarely_alone(world: World, relation: str, landmark: str, bodies: list[str]) -> str | None:
    """The one of the bodies in a direction a viewer takes: 35° off it at most, and the others
    within 55° of it no squarer and no nearer, and 10° further off or 2 cm farther."""
    angles = {b: world.off_axis(b, relation, landmark) for b in bodies}
    fits = [b for b, angle in angles.items() if angle is not None and angle < 55.0]
    best = min(fits, key=lambda b: (angles[b], world.distance(b, landmark)), default=None)
    if best is None or angles[best] > 35.0:
        return None
    near = world.distance(best, landmark)
    for other in fits:
        far = world.distance(other, landmark)
        if other != best and not (angles[other] >= angles[best] and far >= near and (
                angles[other] >= angles[best] + 10.0 or far >= near + 0.02)):
            return None
    return best


def _check_unique(world: World, question) -> None:
    """Re-derive a question's answer from the world's geometry alone."""
    expected = question.expected
    if match := RELATED.search(question.question):
        noun, phrase, words, _ = match.groups()
        noun = _kind(noun)
        relation = next(r for r, p in RELATION_WORDS.items() if p == phrase)
        landmark = _landmark(world, words)
        fits = [b for b in world.bodies if b != landmark
                and (noun == "object" or world.bodies[b].kind == noun)]
        if relation in DIRECTIONS:
            body = _squarely_alone(world, relation, landmark, fits)
        else:
            related = [b for b in fits if world.related(b, relation, landmark)]
            body = related[0] if len(related) == 1 else None
        assert body is not None, (question.question, fits)
        spec = world.bodies[body]
        assert (expected.color or expected.object.color) == spec.color
    elif question.template == "extreme":
        extreme, noun = re.search(rf"the (leftmost|rightmost) {NOUN}\.",
                                  question.question).groups()
        noun = _kind(noun)
        xs = sorted(((world.poses[b].x, world.bodies[b].color) for b in world.bodies
                     if world.bodies[b].kind == noun), reverse=extreme == "rightmost")
        assert abs(xs[0][0] - xs[1][0]) >= EXTREME_MARGIN and xs[0][1] == expected.color
    elif question.template == "which_side":
        side, words, _ = re.search(rf"on the (left|right) side of the (\w+ {NOUN})\?",
                                   question.question).groups()
        landmark = _landmark(world, words)
        fits = [b for b in world.bodies if b != landmark]
        assert _squarely_alone(world, f"{side}_of", landmark, fits), (question.question, fits)
    else:  # a group, left to right, clearly apart
        assert len(expected.objects) == len(set(expected.objects)) >= 2


@settings(max_examples=30, deadline=None)
@given(st.sampled_from(sorted((s, next(iter(SCENES[s].layouts))) for s in SCENES)),
       st.integers(0, 2 ** 31))
def test_every_generated_question_has_exactly_one_answer(scene_layout, seed):
    scene, layout = scene_layout
    world = World(SCENES[scene], layout,
                  sample_offsets(SCENES[scene], layout, np.random.default_rng(seed)))
    found = questions(world)
    assert len(found) >= 10 and len({q.question for q in found}) == len(found)
    for question in found:
        _check_unique(world, question)


def _the(color: str, noun: str) -> lf.Ref:
    return lf.Ref(noun=noun, constraints=(lf.ColorIs(color=color),))


def test_ambiguous_questions_are_rejected():
    grounder = Grounder(DEFAULT)
    # left of the green bowl: the large blue cube squarest (8°, 21 cm), the small blue cylinder
    # nearest (17°, 10 cm): neither is the one a viewer takes
    assert unique_answer(grounder, Ask("which_side", "left_of", _the("green", "bowl"))) is None
    texts = {q.question for q in questions(DEFAULT)}
    assert "Which object is located on the left side of the green bowl?" not in texts
    # right of the blue cube: the blue cylinder squarely (0°, 11 cm), the red cube behind it
    # and right (39°, 14 cm): the cylinder
    assert "Which object is located on the right side of the blue cube?" in texts
    # two cubes side by side within the extreme margin: no leftmost cube, no pair question
    positions = {b: (p.x, p.y, p.z) for b, p in DEFAULT.poses.items()}
    x, y, z = positions["small_red_cube"]
    positions["large_blue_cube"] = (x - EXTREME_MARGIN / 2, y - 0.09, positions[
        "large_blue_cube"][2])
    tied = World(SCENES["scene2"], "default", positions=positions)
    tied_texts = {q.question for q in questions(tied)}
    assert "Output the color of the leftmost cube." not in tied_texts
    assert not any("two cubes" in t for t in tied_texts)
    assert "Output the color of the leftmost cylinder." in tied_texts


EXPECTED = {q.id: q.expected for q, _ in answer_all(DEFAULT)}


@pytest.mark.parametrize("question, answer", [
    ("qa20-01", "A red cylinder."),
    ("qa20-01", "It's the red cylinder, right behind the blue cube."),
    ("qa20-02", "Yellow"),
    ("qa20-02", "The object to the right of the green bowl is yellow."),
    ("qa20-04", "RED."),
    ("qa20-07", "It is a yellow bowl."),
    ("qa20-08", "There is a red cylinder at the back left and a red cube to its right."),
    ("qa20-09", "the small blue cylinder"),
    ("qa20-11", "The cylinder is on the left and the cube is on the right."),
    ("qa20-11", "The red cylinder is to the left of the red cube."),
    ("qa20-14", "The green bowl is on the left, the yellow bowl on the right."),
    ("qa20-14", "The green one."),
    ("qa20-19", "green"),
])
def test_paraphrased_correct_answers_score(question, answer):
    verdict = score(answer, EXPECTED[question])
    assert verdict.correct, verdict.reason


@pytest.mark.parametrize("question, answer, reason", [
    ("qa20-01", "The red cube.", "names cube; expected the red cylinder"),
    ("qa20-02", "green", "names green; expected yellow"),
    ("qa20-02", "I cannot tell.", "names no colour; expected yellow"),
    ("qa20-07", "A bowl.", "does not give the colour; expected the yellow bowl"),
    ("qa20-07", "A yellow cylinder", "names cylinder; expected the yellow bowl"),
    ("qa20-08", "a red cylinder", "does not name the red cube"),
    ("qa20-08", "The red cube is on the left, the red cylinder on the right.",
     "puts the red cube on the left; it is on the right"),
    ("qa20-09", "The blue ball", "names sphere; expected the blue cylinder"),
    ("qa20-11", "The red cube is to the left of the red cylinder.",
     "puts the red cube on the left"),
    ("qa20-14", "They are side by side; the yellow bowl is on the left.",
     "puts the yellow bowl on the left"),
    ("qa20-18", "grey", "names gray; expected blue"),
    ("qa20-05", "red and blue", "names blue, red; expected red"),
])
def test_incorrect_answers_say_what_is_wrong(question, answer, reason):
    verdict = score(answer, EXPECTED[question])
    assert not verdict.correct and reason in verdict.reason


@pytest.mark.slow
def test_vqa_writes_the_probe_and_grades_answers(tmp_path, capsys):
    specs = str(builtin_specs())
    out = tmp_path / "qa20"
    assert main(["vqa", "--qa20", "--out", str(out), "--specs", specs, "--quiet"]) == 0
    records = [json.loads(line) for line in (out / "questions.jsonl").read_text().splitlines()]
    assert [r["answer"] for r in records] == [QA20_ANSWERS[n] for n in range(1, 21)]
    assert (out / records[0]["image"]).is_file()
    lerobot = json.loads((out / "qa_lerobot.jsonl").read_text().splitlines()[0])
    assert lerobot["task"] == records[0]["question"]
    conversation = json.loads((out / "qa_sharegpt.json").read_text())[0]["conversations"]
    assert conversation[1]["value"] == records[0]["answer"]
    answers = tmp_path / "answers.jsonl"
    answers.write_text("".join(json.dumps({"id": r["id"], "prediction": "blue"}) + "\n"
                               for r in records))
    capsys.readouterr()
    assert main(["vqa", "score", str(answers), "--questions", str(out / "questions.jsonl")]) == 0
    text = capsys.readouterr().out
    assert "4/20 correct (20.0%)" in text and "✗ scene2/default/nominal/qa20-03" in text
    answers.write_text('{"id": "x", "prediction": "red"}\n')
    assert main(["vqa", "score", str(answers)]) == 1
    assert f"{answers}:1: question 'x' is not in" in capsys.readouterr().err
    answers.write_text('{"id": "x", "prediction": "red"}\n{oops\n')
    assert main(["vqa", "score", str(answers)]) == 1
    assert f"{answers}:2:2: not JSON" in capsys.readouterr().err


@pytest.mark.slow
def test_generated_probes_repeat_with_their_seed(tmp_path):
    specs = str(builtin_specs())
    for name in ("a", "b"):
        assert main(["vqa", "--scene", "scene1", "--out", str(tmp_path / name), "--count", "7",
                     "--seed", "3", "--specs", specs, "--quiet"]) == 0
    first = (tmp_path / "a" / "questions.jsonl").read_text()
    assert first == (tmp_path / "b" / "questions.jsonl").read_text()
    records = [json.loads(line) for line in first.splitlines()]
    assert len(records) == 7 and {r["seed"] for r in records} == {3, 4}
    assert main(["vqa", "--scene", "scene1", "--out", str(tmp_path / "a"), "--specs",
                 specs]) == 1  # not empty
