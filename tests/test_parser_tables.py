"""The parser's own loop over lark's LALR tables (robofollow.compiler.language.parser) must build exactly
the syntax records that lark's own parser builds from the same grammar, on every instruction of
the corpora and on malformed ones (the same error, or none, at the same token): a lark release
that changes its private table layout fails here, not silently in `parse`."""

from __future__ import annotations

import json
from dataclasses import astuple, is_dataclass
from pathlib import Path

from lark.exceptions import UnexpectedToken

from robofollow.compiler.language import parser
from robofollow.errors import InstructionError, UngrammaticalError
from tests.instruction_cases import CASES

DATA = Path(__file__).parent / "data"
CORPUS = ([text for task in json.loads((DATA / "training_instructions.json").read_text())
           for text in task["paraphrases"]]
          + [text for file in sorted((DATA / "stress").glob("*.json"))
             for entry in json.loads(file.read_text()) for text in entry["rewordings"]]
          + [text for text, _, _ in CASES])


def plain(value):
    """Syntax records as nested tuples (tokens as their text and type), for comparing."""
    if is_dataclass(value):
        return (type(value).__name__, *map(plain, astuple(value, tuple_factory=list)))
    if isinstance(value, list | tuple):
        return tuple(plain(item) for item in value)
    if hasattr(value, "type") and hasattr(value, "text"):
        return ("token", value.type, value.text)
    return value


def by_lark(text: str):
    """lark's records, or where it stopped: (error, column) of the unexpected token."""
    try:
        return plain(parser._lark().parse(text))
    except UnexpectedToken as error:
        return ("error", "end" if error.token.type == "$END" else error.token.column)
    except InstructionError as error:  # an unknown word (the lexicon is the tokenizer)
        return ("error", error.column)


def by_loop(text: str):
    try:
        return plain(parser._syntax(text))
    except UngrammaticalError as error:  # (one at the end is placed at the last word)
        at_end = error.message in ("the instruction ends too early", "the instruction is empty")
        return ("error", "end" if at_end else error.column)
    except InstructionError as error:
        return ("error", error.column)


def test_the_fast_loop_builds_what_lark_builds():
    assert len(CORPUS) > 1000
    differ = [text for text in CORPUS if by_lark(text) != by_loop(text)]
    assert differ == []
    assert sum(by_loop(text)[0] == "error" for text in CORPUS) >= 10  # malformed ones too
