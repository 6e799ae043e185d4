"""The tokenizer: words to terminals, with columns and the two-token decisions."""

import pytest

from robofollow.compiler.language.lexicon import VOCABULARY, tokenize
from robofollow.errors import UnknownWordError


def kinds(text):
    return [(t.type, t.value, t.column) for t in tokenize(text)]


def test_synonyms_share_terminal_and_value():
    assert VOCABULARY["ball"].terminal == VOCABULARY["sphere"].terminal == "NOUN"
    assert VOCABULARY["ball"].value == "sphere"
    assert VOCABULARY["grab"].value == VOCABULARY["grasp"].value == "grasp"
    assert VOCABULARY["put"].value == VOCABULARY["place"].value == "place"


def test_columns_and_original_text_are_kept():
    tokens = tokenize("Grab  the BALL.")
    assert [(t.type, t.value, t.text, t.column) for t in tokens] == [
        ("GRASP", "grasp", "Grab", 1), ("THE", "the", "the", 7), ("NOUN", "sphere", "BALL", 11)]


def test_hyphens_join_known_words_or_split():
    assert kinds("the left-most cube")[1] == ("EXTREME", "leftmost", 5)
    assert kinds("non-leftmost")[:2] == [("NON", "non", 1), ("EXTREME", "leftmost", 5)]
    assert [k[0] for k in kinds("is non-empty")] == ["IS", "NON", "EMPTY"]


@pytest.mark.parametrize("text,expected", [
    ("isn't", ["IS", "NOT"]), ("isn’t", ["IS", "NOT"]), ("don't", ["DO", "NOT"]),
    ("doesn't", ["DOES", "NOT"]), ("nonempty", ["NON", "EMPTY"]),
])
def test_contractions_expand(text, expected):
    assert [t.type for t in tokenize(text)] == expected
    assert {t.column for t in tokenize(text)} == {1}


def test_and_before_a_modifier_is_a_modifier_conjunction():
    assert [t.type for t in tokenize("red and behind") if t.value == "and"] == ["AND_MOD"]
    assert [t.type for t in tokenize("cube and place") if t.value == "and"] == ["AND"]


def test_separators_before_otherwise_and_if_are_absorbed():
    types = [t.type for t in tokenize("red; otherwise blue. If yes, green")]
    assert "SEMICOLON" not in types and "PERIOD" not in types
    assert types.count("COMMA") == 1


def test_final_punctuation_is_dropped():
    assert [t.type for t in tokenize("Pick up the cube!")][-1] == "NOUN"
    assert [t.type for t in tokenize("Pick up. The cube.")].count("PERIOD") == 1


def test_unknown_word_reports_column_within_a_hyphenated_word():
    with pytest.raises(UnknownWordError) as caught:
        tokenize("pick up the non-dragon")
    assert caught.value.column == 17 and caught.value.length == 6
