"""parse(text) -> canonical logical form, with the project's own errors.

lark builds the LALR(1) tables (strict: conflict-free) and the syntax callbacks; a small loop
of our own drives them over the lexicon's tokens, which saves lark's per-token bookkeeping on
the hot path (the interactive parser, for error suggestions, is lark's own).
"""

from __future__ import annotations

from functools import cache

from lark import Lark, UnexpectedToken
from lark.lexer import Lexer
from lark.parsers.lalr_analysis import Shift

from robofollow.compiler.language import lf
from robofollow.compiler.language.coverage import unsupported_action
from robofollow.compiler.language.lark_tables import cached_lark
from robofollow.compiler.language.lexicon import (
    VOCABULARY,
    WordToken,
    tokenize,
    words_of,
)
from robofollow.compiler.language.semantics import Semantics
from robofollow.compiler.language.syntax import ToSyntax
from robofollow.errors import (
    InstructionError,
    UngrammaticalError,
    UnknownWordError,
    UnsupportedConstructError,
)
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
    """The parser (its tables from the cache folder: lark_tables.py)."""
    return cached_lark("instruction", grammar_text("instruction.lark"), lexer=_WordLexer,
                       transformer=ToSyntax(), strict=True)


class _States(dict):
    """The parse table as {state: {symbol: (True, next state) | (False, (size, goto symbol,
    callback))}}, each row converted from lark's when first used (a process uses few of the
    ~900)."""

    def __init__(self, table, callbacks):
        super().__init__()
        self._table, self._callbacks = table, callbacks

    def __missing__(self, state):
        # plain str keys: lark's rule names are Token objects, slower to hash and compare
        row = self[state] = {
            str(symbol): (True, arg) if action is Shift else
            (False, (len(arg.expansion), str(arg.origin.name), self._callbacks[arg]))
            for symbol, (action, arg) in self._table.states[state].items()}
        return row


@cache
def _machine() -> tuple[_States, int, int]:
    """The parse table (_States), the start state and the accepting state."""
    inner = _lark().parser.parser.parser
    table = inner.parse_table
    return (_States(table, inner.callbacks), table.start_states["start"],
            table.end_states["start"])


def _syntax(text: str):
    """The syntax records of an instruction (raises UngrammaticalError)."""
    states, start, accept = _machine()
    tokens = tokenize(text)
    last = tokens[-1] if tokens else None
    end = WordToken("$END", "", "", last.column if last else 1, last.end_column if last else 1)
    stack, values = [start], []
    for token in tokens + [end]:
        while True:
            row = states[stack[-1]]
            entry = row.get(token.type)
            if entry is None:
                raise _ungrammatical(token, [s for s in row if s.isupper()], text)
            shift, arg = entry
            if shift:
                stack.append(arg)
                values.append(token)
                break
            size, goto, callback = arg
            if size:
                children = values[-size:]
                del values[-size:], stack[-size:]
            else:
                children = []
            values.append(callback(children))
            stack.append(states[stack[-1]][goto][1])
            if token is end and stack[-1] == accept:
                return values[-1]


def terminal_name(terminal: str) -> str:
    if terminal in _TERMINAL_NAMES:
        return _TERMINAL_NAMES[terminal]
    return repr(words_of(terminal)[0])


def _ungrammatical(token: WordToken, expected_terminals, text: str) -> UngrammaticalError:
    expected = sorted({terminal_name(t) for t in expected_terminals})
    if len(expected) > _MAX_EXPECTED:
        expected = expected[:_MAX_EXPECTED] + ["..."]
    if token.type == "$END":  # placed at the last word
        column = token.end_column or 1
        message = ("the instruction is empty" if not text.strip()
                   else "the instruction ends too early")
        return UngrammaticalError(message, text=text, column=column, expected=tuple(expected))
    construct = unsupported_action(token.text) if "PICK" in expected_terminals else None
    if construct is not None:
        return UnsupportedConstructError(
            f"not supported: {construct.name} ({token.text!r}); say instead: "
            f"{construct.instead}", text=text, column=token.column,
            length=token.end_column - token.column)
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
        syntax = _syntax(text)
    except UnknownWordError as error:
        raise _fitting(error) from None
    return Semantics(text).instruction(syntax)
