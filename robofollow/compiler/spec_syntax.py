"""The spec grammar (grammar/spec.lark): a file's text -> its parse tree, or the syntax error
at the first place it fails."""

from __future__ import annotations

from functools import cache

from lark import Lark, Tree, UnexpectedCharacters, UnexpectedEOF, UnexpectedToken

from robofollow.compiler.spec import Source
from robofollow.compiler.spec_files import Sources, spec_error, split_lines
from robofollow.errors import SpecError
from robofollow.resources import grammar_text


@cache
def _parser() -> Lark:
    return Lark(grammar_text("spec.lark"), parser="lalr", strict=True, propagate_positions=True)


def parse_spec(text: str, file: str, sources: Sources) -> Tree | SpecError:
    """The parse tree of a spec file's text, or its syntax error."""
    try:
        return _parser().parse(text)
    except (UnexpectedEOF, UnexpectedToken) as error:
        if isinstance(error, UnexpectedEOF) or error.token.type == "$END":
            lines = split_lines(text.rstrip())
            return SpecError("syntax", "the file ends too early" + _expected(error.expected),
                             file=file, line=len(lines), column=len(lines[-1]) + 1,
                             source_line=lines[-1])
        token = error.token
        return spec_error("syntax", f"unexpected {token!s:.30}" + _expected(error.expected),
                          Source(file=file, line=token.line, column=token.column), sources,
                          len(token))
    except UnexpectedCharacters as error:
        return spec_error("syntax", f"unexpected character {text[error.pos_in_stream]!r}"
                          + _expected(error.allowed),
                          Source(file=file, line=error.line, column=error.column), sources)


def _expected(terminals) -> str:
    """Expected terminals as a reader knows them: '}' rather than RBRACE."""
    names = []
    for name in sorted(terminals):
        pattern = _parser().get_terminal(name).pattern
        names.append(repr(pattern.value) if pattern.type == "str" else name.lower())
    return f" (expected: {', '.join(sorted(names)[:12])})" if names else ""
