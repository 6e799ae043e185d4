"""Bad instructions: each fails with the project's own error type at the first bad word."""

import pytest

from robofollow.compiler.language.parser import parse
from robofollow.errors import (
    InstructionError,
    RoboFollowError,
    UngrammaticalError,
    UnknownWordError,
    UnsupportedConstructError,
)
from tests.instruction_cases import CASES, UNGRAMMATICAL, UNKNOWN, UNSUPPORTED


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


def test_a_description_a_logical_form_rejects_says_why():
    with pytest.raises(UnsupportedConstructError) as caught:
        parse("Pick up the middle cube that is the second from the left.")
    assert caught.value.message == "one description takes at most one ordinal or 'middle'"
    assert caught.value.column == 9
