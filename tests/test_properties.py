"""Properties over generated logical forms and text."""

import pytest
from hypothesis import given, note

from robofollow.compiler.language import lf
from robofollow.compiler.language.parser import parse
from robofollow.compiler.language.realize import STYLES, realize
from robofollow.errors import InstructionError
from tests import strategies


@pytest.mark.parametrize("style", sorted(STYLES))
@given(instruction=strategies.instructions)
def test_realized_english_parses_back_to_the_same_form(style, instruction):
    text = realize(instruction, style)
    note(text)
    assert parse(text) == instruction


@given(instruction=strategies.instructions)
def test_json_round_trip_is_lossless_and_canonical(instruction):
    data = lf.to_json(instruction)
    back = lf.from_json(data)
    assert back == instruction
    assert lf.to_json(back) == data


@given(text=strategies.word_salad | strategies.any_text)
def test_any_text_raises_only_instruction_errors(text):
    try:
        parse(text)
    except InstructionError as error:
        assert 1 <= error.column <= len(text) + 1
