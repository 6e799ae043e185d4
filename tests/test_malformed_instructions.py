"""Bad instructions: each fails with the project's own error type at the first bad word."""

import pytest

from robofollow.compiler.parser import parse
from robofollow.errors import (
    InstructionError,
    RoboFollowError,
    UngrammaticalError,
    UnknownWordError,
    UnsupportedConstructError,
)

UNKNOWN, UNGRAMMATICAL, UNSUPPORTED = UnknownWordError, UngrammaticalError, UnsupportedConstructError

CASES = [
    # unknown words
    ("Pick up the red cyllinder.", UNKNOWN, 17),
    ("Pick up the purple dragon.", UNKNOWN, 20),
    ("Pick up the cube 3.", UNKNOWN, 18),
    ("Pick up the red cube with your left leg.", UNKNOWN, 37),
    ("Pick up the cube @ the bowl.", UNKNOWN, 18),
    ("Pick up the cube that is larger than the ball.", UNSUPPORTED, 33),
    # ungrammatical order, or cut short
    ("", UNGRAMMATICAL, 1),
    ("   ", UNGRAMMATICAL, 1),
    ("Pick up the the red cube.", UNGRAMMATICAL, 13),
    ("Pick up the red cube and", UNGRAMMATICAL, 25),
    ("the red cube pick up", UNGRAMMATICAL, 5),  # "the" may open "the task is to"
    ("Place it behind.", UNGRAMMATICAL, 16),
    ("If the bowl, pick up the cube.", UNGRAMMATICAL, 12),
    ("If there is an object in the bowl pick up the cube otherwise", UNGRAMMATICAL, 61),
    ("Check whether the bowl is empty. If yes, pick up the cube.", UNGRAMMATICAL, 58),
    ("Pick up the cube before pick up the ball.", UNGRAMMATICAL, 25),
    ("Pick up the cube on the left of.", UNGRAMMATICAL, 32),
    # grammatical, but no meaning RoboFollow can represent
    ("Use your left arm to pick up the cube with your right arm.", UNSUPPORTED, 39),
    ("Pick it up.", UNSUPPORTED, 6),
    ("Push it towards the bowl.", UNSUPPORTED, 6),
    ("Pick up that cube.", UNSUPPORTED, 9),
    ("Place the red cube.", UNSUPPORTED, 1),
    ("Push the red cube.", UNSUPPORTED, 1),
    ("Pass over the red slab.", UNSUPPORTED, 1),
    ("Avoid the red slab.", UNSUPPORTED, 1),
    ("Pick up the red slab and pass over the green slab.", UNSUPPORTED, 26),
    ("Move the red slab over the green slab.", UNSUPPORTED, 19),
    ("Pick up the cube with the short side facing front.", UNSUPPORTED, 18),
    ("Pick up the cube onto the bowl.", UNSUPPORTED, 18),
    ("Pick up the cube in the direction of the ball.", UNSUPPORTED, 18),
    ("Pick up the cube that is not larger.", UNSUPPORTED, 18),
    ("Place the cube touching the bowl.", UNSUPPORTED, 16),
    ("Put the cube behind the ball behind it.", UNSUPPORTED, 37),
    ("Use your left arm.", UNSUPPORTED, 1),
    ("Pick up the object that is a cylinder that is a cube.", UNSUPPORTED, 39),
    ("Pick up the cube and place it behind the ball, short side facing front, "
     "long side facing right.", UNSUPPORTED, 73),
]


def test_there_are_at_least_twenty_five():
    assert len(CASES) >= 25
    assert {kind for _, kind, _ in CASES} == {UNKNOWN, UNGRAMMATICAL, UNSUPPORTED}


@pytest.mark.parametrize("text,kind,column", CASES, ids=[t[:45] or "empty" for t, _, _ in CASES])
def test_malformed_instruction_error_type_and_column(text, kind, column):
    with pytest.raises(kind) as caught:
        parse(text)
    error = caught.value
    assert isinstance(error, InstructionError) and isinstance(error, RoboFollowError)
    assert error.column == column
    assert error.text == text


def test_unknown_word_suggests_the_closest_words():
    with pytest.raises(UnknownWordError) as caught:
        parse("Pick up the red cyllinder.")
    assert caught.value.suggestions[0] == "cylinder"
    rendered = caught.value.render().splitlines()
    assert rendered[1] == "  Pick up the red cyllinder."
    assert rendered[2] == "  " + " " * 16 + "^" * 9
    assert "did you mean: 'cylinder'" in rendered[3]


def test_ungrammatical_error_says_what_was_expected():
    with pytest.raises(UngrammaticalError) as caught:
        parse("Pick up the the red cube.")
    assert "a colour" in caught.value.expected
    assert "'leftmost' or 'rightmost'" in caught.value.expected
    with pytest.raises(UngrammaticalError) as caught:
        parse("Push the cube towards")
    assert caught.value.message == "the instruction ends too early"
    assert "'the'" in caught.value.expected
