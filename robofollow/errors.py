"""RoboFollow's errors: one root, typed subclasses that say where and what."""

from __future__ import annotations

import difflib
from collections.abc import Iterable


class RoboFollowError(Exception):
    """Root of every error RoboFollow raises on bad input."""

    code = "error"

    def render(self) -> str:
        """The message as shown to a person."""
        return str(self)


class UsageError(RoboFollowError):
    """A command-line argument that cannot be used as given: exit status 2, as for the
    arguments argparse itself rejects."""


class InstructionError(RoboFollowError):
    """An instruction that cannot be turned into a logical form; `column` is 1-based."""

    code = "instruction"

    def __init__(self, message: str, *, text: str, column: int, length: int = 1,
                 expected: tuple[str, ...] = (), suggestions: tuple[str, ...] = ()):
        super().__init__(message)
        self.message = message
        self.text = text
        self.column = column
        self.length = max(length, 1)
        self.expected = expected
        self.suggestions = suggestions

    def __str__(self) -> str:
        return f"column {self.column}: {self.message}"

    def render(self) -> str:
        lines = [f"error: {self.message} (column {self.column})",
                 f"  {self.text}",
                 "  " + " " * (self.column - 1) + "^" * self.length]
        return "\n".join(lines + [f"  {hint}" for hint in self.hints()])

    def hints(self) -> list[str]:
        """What may stand at the column, and the known words a misspelt one may stand for."""
        hints = []
        if self.expected:
            hints.append("expected: " + ", ".join(self.expected))
        if self.suggestions:
            hints.append("did you mean: " + ", ".join(repr(s) for s in self.suggestions) + "?")
        return hints

    def to_dict(self) -> dict:
        return {"type": self.code, "column": self.column, "message": self.message}


class UnknownWordError(InstructionError):
    """A word (or character) the instruction language does not know."""

    code = "unknown_word"


class UngrammaticalError(InstructionError):
    """Known words in an order the grammar does not allow (or an instruction cut short)."""

    code = "ungrammatical"


class UnsupportedConstructError(InstructionError):
    """Grammatical, but with no meaning RoboFollow can represent (a dangling 'it', two arms, ...)."""

    code = "unsupported"


class SpecError(RoboFollowError):
    """One problem in a spec file, at a 1-based line and column; `hints` are shown under the
    caret."""

    def __init__(self, code: str, message: str, *, file: str, line: int, column: int,
                 source_line: str = "", length: int = 1, hints: tuple[str, ...] = (),
                 severity: str = "error"):
        super().__init__(message)
        self.code = code
        self.severity = severity  # "error", or "warning": a problem that stops nothing
        self.message = message
        self.file = file
        self.line = line
        self.column = column
        self.source_line = source_line
        self.length = max(length, 1)
        self.hints = hints

    def __str__(self) -> str:
        return (f"{self.file}:{self.line}:{self.column}: {self.severity}[{self.code}]: "
                f"{self.message}")

    def render(self) -> str:
        lines = [str(self)]
        if self.source_line:
            lines += [f"  {self.source_line}", f"  {' ' * (self.column - 1)}{'^' * self.length}"]
        return "\n".join(lines + [f"  {hint}" for hint in self.hints])


class SpecErrors(RoboFollowError):
    """Every problem found in a set of spec files, reported together."""

    code = "spec"

    def __init__(self, errors: list[SpecError]):
        super().__init__(f"{len(errors)} error(s) in the specs")
        self.errors = errors

    def render(self) -> str:
        return "\n".join([e.render() for e in self.errors] +
                         [f"{counted(len(self.errors), 'error')} in the specs"])


def counted(count: int, noun: str) -> str:
    """'1 scene', '4 scenes': a count and its noun in the right number."""
    return f"{count} {noun if count == 1 else noun + 's'}"


def did_you_mean(name: str, known: Iterable[str]) -> str:
    """"did you mean 'x'?" for the known name closest to a misspelt one ('' when none is
    close)."""
    close = difflib.get_close_matches(name, list(known), n=1)
    return f"did you mean {close[0]!r}?" if close else ""


def error_text(error: BaseException) -> str:
    """An exception in words: 'Type: message', or its repr when it says nothing."""
    text = str(error)
    return f"{type(error).__name__}: {text}" if text else repr(error)


NAMED = 5  # episodes named in a warning or an error


def named(items: list[str]) -> str:
    """The first NAMED items, and how many more."""
    more = f" and {len(items) - NAMED} more" if len(items) > NAMED else ""
    return ", ".join(items[:NAMED]) + more
