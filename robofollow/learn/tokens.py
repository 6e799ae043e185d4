"""What a baseline reads of the instruction, as token ids.

`text` reads the instruction's words; `form` reads its canonical logical form as the parser
prints it (`pick(left, cylinder[red])`), brackets and commas included, so that paraphrases of one
task read alike; `blind` reads nothing. The objects kinds read as their language does
(`objects-text` as `text`, `objects-form` as `form`). Token 0 pads, token 1 stands for a word
the vocabulary lacks (or an instruction the parser rejects, for `form`).
"""

from __future__ import annotations

import re

import numpy as np

from robofollow.compiler.language.notation import notation
from robofollow.compiler.language.parser import parse
from robofollow.errors import InstructionError
from robofollow.learn.options import OBJECTS_PREFIX

PAD, UNKNOWN = 0, 1
MAX_TOKENS = 32
_WORD = re.compile(r"[a-z0-9]+")
_FORM = re.compile(r"[a-z0-9]+|[^\sa-z0-9]")


def words(kind: str, instruction: str) -> list[str]:
    """The tokens `kind` reads of an instruction."""
    kind = kind.removeprefix(OBJECTS_PREFIX)
    if kind == "blind":
        return []
    if kind == "text":
        return _WORD.findall(instruction.lower())
    try:
        form = notation(parse(instruction))
    except InstructionError:
        return ["<unparsed>"]
    return _FORM.findall(form.lower())


def vocabulary(kind: str, instructions: list[str]) -> list[str]:
    """Every token of the training instructions, sorted, after the two reserved ones."""
    seen = sorted({word for text in set(instructions) for word in words(kind, text)})
    return ["<pad>", "<unknown>"] + [word for word in seen if word != "<unparsed>"]


def encode(kind: str, instruction: str, vocab: list[str]) -> np.ndarray:
    """[MAX_TOKENS] int32 ids, padded with PAD (longer instructions are cut)."""
    index = {word: i for i, word in enumerate(vocab)}
    ids = [index.get(word, UNKNOWN) for word in words(kind, instruction)][:MAX_TOKENS]
    return np.array(ids + [PAD] * (MAX_TOKENS - len(ids)), np.int32)
