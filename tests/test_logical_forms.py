"""Logical forms are canonical by construction and round-trip through JSON."""

import pytest
from pydantic import ValidationError

from robofollow.compiler.language import lf
from robofollow.compiler.language.parser import parse

RED = lf.ColorIs(color="red")
BALL = lf.Ref(noun="sphere")


def test_constraints_are_a_set():
    one = lf.Ref(noun="cube", constraints=(lf.Related(relation="left_of", landmark=BALL), RED, RED))
    other = lf.Ref(noun="cube", constraints=(RED, lf.Related(relation="left_of", landmark=BALL)))
    assert one == other
    assert lf.to_json(lf.Pick(object=one)) == lf.to_json(lf.Pick(object=other))


def test_relations_nest_one_level():
    nested = lf.Ref(noun="block", constraints=(lf.Related(relation="left_of", landmark=BALL),))
    with pytest.raises(ValidationError):
        lf.Related(relation="behind", landmark=nested)
    # a destination's landmark may carry relations
    lf.Placement(relation="behind", landmark=nested)


def test_json_round_trip_of_a_conditional():
    form = parse("Check whether the bowl is non-empty. If yes, pick up the blue sphere with your "
                 "left arm; if not, stack the cylinder from the right cube on the yellow "
                 "cylinder with your right arm.")
    assert lf.from_json(lf.to_json(form)) == form
    assert form == lf.Conditional(
        condition=lf.Exists(ref=lf.Ref(noun="object", constraints=(
            lf.Related(relation="in", landmark=lf.Ref(noun="bowl")),))),
        then=lf.Pick(arm="left", object=lf.Ref(noun="sphere", constraints=(
            lf.ColorIs(color="blue"),))),
        otherwise=lf.Place(
            arm="right",
            object=lf.Ref(noun="cylinder", constraints=(lf.Related(
                relation="on", landmark=lf.Ref(noun="cube", constraints=(
                    lf.ExtremeIs(extreme="rightmost"),))),)),
            destination=lf.Placement(relation="on", landmark=lf.Ref(
                noun="cylinder", constraints=(lf.ColorIs(color="yellow"),)))))


@pytest.mark.parametrize("a,b", [
    ("Grasp the ball.", "Pick up the sphere."),
    ("Grab the red ball using your left arm.", "Using your left arm, pick up the red sphere."),
    ("Put the cube into the bowl.", "Place the cube in the bowl."),
    ("Pick up the cube that is leftmost.", "Among the cubes, pick up the one on the left."),
    ("Pick up the left cube.", "Pick up the cube in the leftmost position."),
    ("Pick up the non-leftmost ball.", "Pick up the ball that is not on the left side."),
    ("Stack the cube onto the cylinder.", "Place the cube on top of the cylinder."),
    ("Push the cube in the direction of the ball.", "Push the cube toward the ball."),
    ("If the bowl is non-empty, pick up the cube.", "When there is an object in the bowl, "
                                                   "pick up the cube."),
    ("Pick up the cube that is red and behind the ball.",
     "Pick up the red cube that is behind the ball."),
])
def test_synonyms_and_word_order_collapse(a, b):
    assert lf.to_json(parse(a)) == lf.to_json(parse(b))


def test_forms_are_frozen():
    with pytest.raises(ValidationError):
        BALL.noun = "cube"
