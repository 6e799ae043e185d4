"""parse(text) -> canonical logical form, with the project's own errors."""

from __future__ import annotations

from functools import cache

from lark import Lark, UnexpectedToken
from lark.lexer import Lexer

from robofollow.compiler import lf
from robofollow.compiler.lexicon import VOCABULARY, tokenize, words_of
from robofollow.compiler.semantics import Semantics
from robofollow.compiler.syntax import ToSyntax
from robofollow.errors import InstructionError, UngrammaticalError, UnknownWordError
from robofollow.resources import grammar_text

# How an expected terminal is named in error messages (others list their words).
_TERMINAL_NAMES = {
    "NOUN": "a noun (block, cube, cylinder, sphere, slab, bowl, object, ...)",
    "NOUNS": "a plural noun (cubes, objects, ...)",
    "COLOR": "a colour", "SIZE": "'larger' or 'smaller'",
    "EXTREME": "'leftmost' or 'rightmost'", "LENGTH": "'short' or 'long'",
    "COMMA": "','", "SEMICOLON": "';'", "PERIOD": "'.'", "AND_MOD": "'and'",
    "$END": "the end of the instruction",
}
_MAX_EXPECTED = 20


class _WordLexer(Lexer):
    """Feeds lark the lexicon's word tokens."""

    def __init__(self, lexer_conf):
        pass

    def lex(self, text: str):
        return iter(tokenize(text))


@cache
def _lark() -> Lark:
    return Lark(grammar_text("instruction.lark"), parser="lalr", lexer=_WordLexer,
                transformer=ToSyntax(), strict=True)


def terminal_name(terminal: str) -> str:
    if terminal in _TERMINAL_NAMES:
        return _TERMINAL_NAMES[terminal]
    return repr(words_of(terminal)[0])


def _ungrammatical(error: UnexpectedToken, text: str) -> UngrammaticalError:
    expected = sorted({terminal_name(t) for t in error.expected})
    if len(expected) > _MAX_EXPECTED:
        expected = expected[:_MAX_EXPECTED] + ["..."]
    token = error.token
    if token.type == "$END":  # lark places it at the last word
        column = token.end_column or 1
        message = ("the instruction is empty" if not text.strip()
                   else "the instruction ends too early")
        return UngrammaticalError(message, text=text, column=column, expected=tuple(expected))
    return UngrammaticalError(f"unexpected {token.text!r} here", text=text, column=token.column,
                              length=token.end_column - token.column, expected=tuple(expected))


def _fitting(error: UnknownWordError) -> UnknownWordError:
    """Keep only the suggestions the grammar accepts where the unknown word stands."""
    if not error.suggestions:
        return error
    try:
        interactive = _lark().parse_interactive(error.text[:error.column - 1])
        interactive.exhaust_lexer()
        accepted = interactive.accepts()
    except (UnexpectedToken, InstructionError):  # the words before it are wrong too
        return error
    error.suggestions = tuple(word for word in error.suggestions
                              if word not in VOCABULARY or VOCABULARY[word].terminal in accepted)
    return error


def parse(text: str) -> lf.Instruction:
    """Parse one instruction into its canonical logical form.

    Raises UnknownWordError, UngrammaticalError or UnsupportedConstructError (all
    InstructionError) with the 1-based column of the first bad word.
    """
    try:
        syntax = _lark().parse(text)
    except UnexpectedToken as error:
        raise _ungrammatical(error, text) from None
    except UnknownWordError as error:
        raise _fitting(error) from None
    return Semantics(text).instruction(syntax)
