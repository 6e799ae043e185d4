"""RoboFollow's errors: one root, typed subclasses that say where and what."""

from __future__ import annotations


class RoboFollowError(Exception):
    """Root of every error RoboFollow raises on bad input."""

    code = "error"

    def render(self) -> str:
        """The message as shown to a person."""
        return str(self)


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
        if self.expected:
            lines.append("  expected: " + ", ".join(self.expected))
        if self.suggestions:
            lines.append("  did you mean: " + ", ".join(repr(s) for s in self.suggestions) + "?")
        return "\n".join(lines)

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
    """One problem in a spec file, at a 1-based line and column."""

    def __init__(self, code: str, message: str, *, file: str, line: int, column: int,
                 source_line: str = "", length: int = 1):
        super().__init__(message)
        self.code = code
        self.message = message
        self.file = file
        self.line = line
        self.column = column
        self.source_line = source_line
        self.length = max(length, 1)

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.column}: error[{self.code}]: {self.message}"

    def render(self) -> str:
        if not self.source_line:
            return str(self)
        return (f"{self}\n  {self.source_line}\n"
                f"  {' ' * (self.column - 1)}{'^' * self.length}")


class SpecErrors(RoboFollowError):
    """Every problem found in a set of spec files, reported together."""

    code = "spec"

    def __init__(self, errors: list[SpecError]):
        super().__init__(f"{len(errors)} error(s) in the specs")
        self.errors = errors

    def render(self) -> str:
        count = len(self.errors)
        return "\n".join([e.render() for e in self.errors] +
                         [f"{count} error{'s' if count != 1 else ''} in the specs"])


def error_text(error: BaseException) -> str:
    """An exception in words: 'Type: message', or its repr when it says nothing."""
    text = str(error)
    return f"{type(error).__name__}: {text}" if text else repr(error)
