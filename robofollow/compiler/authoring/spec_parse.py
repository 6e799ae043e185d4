"""A spec file's text -> its scenes' syntax records (spec_syntax.py), or its syntax error at the
first place it fails, said as a person reads it: what may stand there, and a word that is not
a statement of its place (a scene's, or a layout's operations) named as such, with the
statement it most likely stands for."""

from __future__ import annotations

from lark import Token, Tree, UnexpectedCharacters, UnexpectedEOF, UnexpectedToken

from robofollow.compiler.authoring.spec_files import Sources, spec_error, split_lines
from robofollow.compiler.authoring.spec_syntax import BodyNode, SceneNode, spec_parser
from robofollow.compiler.scene.spec import Source
from robofollow.errors import SpecError, did_you_mean

# as grammar/spec.lark orders them
SCENE_STATEMENTS = ("point", "object", "fixture", "jitter", "set", "layout", "task", "test",
                    "split")
LAYOUT_OPERATIONS = ("at", "on", "in", "swap", "move", "remove", "put", "recolor")
PLACEMENTS = ("at", "on", "in")  # a layout operation that starts with the body's name
_SCENE_START = {"OBJECT", "LAYOUT", "TASK"}  # expected where a scene statement may start


def parse_spec(text: str, file: str, sources: Sources) -> list[SceneNode] | SpecError:
    """The scenes of a spec file's text, or its syntax error."""
    try:
        return spec_parser().parse(text)
    except (UnexpectedEOF, UnexpectedToken) as error:
        if isinstance(error, UnexpectedEOF) or error.token.type == "$END":
            lines = split_lines(text.rstrip())
            return SpecError("syntax", "the file ends too early" + _expected(error.expected),
                             file=file, line=len(lines), column=len(lines[-1]) + 1,
                             source_line=lines[-1])
        message, token = _unknown_statement(error) or _unexpected(error)
        return spec_error("syntax", message, Source(file=file, line=token.line,
                                                    column=token.column), sources, len(token))
    except UnexpectedCharacters as error:
        return spec_error("syntax", f"unexpected character {text[error.pos_in_stream]!r}"
                          + _expected(error.allowed),
                          Source(file=file, line=error.line, column=error.column), sources)


def _unexpected(error: UnexpectedToken) -> tuple[str, Token]:
    """'unexpected X (expected: ...)'; for a name, the expected word it most likely stands
    for."""
    token = error.token
    hint = did_you_mean(str(token), _words(error.expected)) if token.type == "NAME" else ""
    return (f"unexpected {token!s:.30}" + (f"; {hint}" if hint else "")
            + _expected(error.expected), token)


def _unknown_statement(error: UnexpectedToken) -> tuple[str, Token] | None:
    """A name where a statement starts that is no statement of its place, and the name itself
    (the parser stops at the word after a name it took for a body or an attribute)."""
    token, expected = error.token, error.expected
    stack = error.interactive_parser.parser_state.value_stack
    before = stack[-1] if stack else None
    if token.type != "NAME":
        return None
    if _SCENE_START <= expected:
        return _unknown("statement", token, SCENE_STATEMENTS, "a scene holds"), token
    if not (isinstance(before, Token) and before.type == "NAME"):
        return None
    if expected == {"AT", "IN", "ON"} and before in _declared_bodies(stack):
        return _unknown(f"placement of {before}", token, PLACEMENTS,
                        "a body is placed with"), token
    if expected == {"AT", "IN", "ON"}:
        return _unknown("layout operation", before, LAYOUT_OPERATIONS,
                        "layout operations"), before
    if expected == {"EQUAL"}:  # after a statement's attributes: `before` starts another
        return _unknown("statement", before, SCENE_STATEMENTS, "a scene holds",
                        "; an attribute is written name=value"), before
    return None


def _unknown(what: str, word: Token, known: tuple[str, ...], listed: str, note: str = "") -> str:
    hint = did_you_mean(str(word), known)
    return (f"unknown {what} {str(word)!r}" + (f"; {hint}" if hint else "")
            + f" ({listed}: {', '.join(known)}{note})")


def _declared_bodies(stack: list) -> set[str]:
    """The names of the bodies declared so far in the scene being parsed."""
    values = [child for value in stack
              for child in (value.children if isinstance(value, Tree) else [value])]
    return {str(value.name) for value in values if isinstance(value, BodyNode)}


def _words(terminals) -> list[str]:
    """The keywords among expected terminals."""
    patterns = (spec_parser().get_terminal(name).pattern for name in sorted(terminals))
    return [p.value for p in patterns if p.type == "str" and p.value.isidentifier()]


def _expected(terminals) -> str:
    """Expected terminals as a reader knows them: '}' rather than RBRACE."""
    names = []
    for name in sorted(terminals):
        pattern = spec_parser().get_terminal(name).pattern
        names.append(repr(pattern.value) if pattern.type == "str" else name.lower())
    return f" (expected: {', '.join(sorted(names)[:12])})" if names else ""
