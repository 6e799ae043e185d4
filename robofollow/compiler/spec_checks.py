"""The checks of what a spec writes that scenes and layouts share: each problem is a SpecError
at the place it is written; every number is finite and within its named limits (spec.py),
positions are on the table top, and an attribute is given once."""

from __future__ import annotations

import math

from lark import Token, Tree

from robofollow.compiler.spec import Source
from robofollow.compiler.spec_files import Sources, spec_error
from robofollow.compiler.workspace import table_bounds
from robofollow.errors import SpecError


class Checks:
    """Problems found so far, located in the file being read."""

    def __init__(self):
        self.errors: list[SpecError] = []
        self.sources = Sources()
        self.file = ""

    def error(self, code: str, message: str, where: Token | Tree | Source,
              length: int | None = None):
        if isinstance(where, Source):
            file, line, column, size = where.file, where.line, where.column, 1
        elif isinstance(where, Token):
            file, line, column, size = self.file, where.line, where.column, len(where)
        else:
            file, line, column = self.file, where.meta.line, where.meta.column
            size = 1
        self.errors.append(spec_error(code, message, Source(file=file, line=line, column=column),
                                      self.sources, length or size))

    def source(self, token: Token) -> Source:
        return Source(file=self.file, line=token.line, column=token.column)

    def attributes(self, nodes: list[Tree], allowed: tuple[str, ...]) -> dict[str, Tree]:
        found: dict[str, Tree] = {}
        for node in nodes:
            key = node.children[0]
            if key not in allowed:
                self.error("unknown-attribute", f"unknown attribute {key!s} here (expected one "
                                                f"of: {', '.join(allowed)})", key)
            elif key in found:
                self.error("duplicate-attribute", f"{key!s} is given twice", key)
            else:
                found[str(key)] = node
        return found

    def checked(self, token: Token, what: str, bounds: tuple[float, float], unit: str = "",
                whole: bool = False) -> float | None:
        """The number written at `token`, or None (reported there) when it is not finite,
        not within `bounds` or, for a count, not a whole number."""
        value, (low, high) = float(token), bounds
        if not math.isfinite(value):
            self.error("bad-value", f"{what} = {_shown(token)} is not a finite number; it must "
                       f"be in [{low:g}, {high:g}]{unit}", token)
        elif not low <= value <= high:
            self.error("bad-value", f"{what} = {_shown(token)} is out of range: it must be in "
                       f"[{low:g}, {high:g}]{unit}", token)
        elif whole and value != int(value):
            self.error("bad-value", f"{what} = {_shown(token)} must be a whole number", token)
        else:
            return value
        return None

    def number(self, node: Tree, bounds: tuple[float, float], unit: str = "",
               whole: bool = False) -> float | None:
        """An attribute that takes one number (checked as `checked` does)."""
        key, value = node.children
        if value.data != "number":
            self.error("bad-value", f"{key!s} takes a number", key)
            return None
        return self.checked(value.children[0], str(key), bounds, unit, whole)

    def numbers(self, node: Tree, count: int, bounds: tuple[float, float],
                unit: str = "") -> tuple[float, ...] | None:
        """An attribute that takes `count` numbers: (a, b, c)."""
        key, value = node.children
        items = value.children if value.data == "values" else [value]
        if len(items) != count or any(i.data != "number" for i in items):
            self.error("bad-value", f"{key!s} takes {count} numbers in [{bounds[0]:g}, "
                       f"{bounds[1]:g}]{unit}: ({', '.join(['n'] * count)})", key)
            return None
        numbers = [self.checked(i.children[0], str(key), bounds, unit) for i in items]
        return None if None in numbers else tuple(numbers)

    def coordinates(self, node: Tree, what: str) -> tuple[float, float] | None:
        """(x, y) as written, or None (reported at the number) when a coordinate is not finite
        or the position is not on the table top."""
        tokens = node.children
        values = [float(token) for token in tokens]
        for token, value, axis in zip(tokens, values, "xy", strict=True):
            if not math.isfinite(value):
                self.error("bad-value", f"{what}: {axis} = {_shown(token)} is not a finite "
                           "number", token)
                return None
        low_x, high_x, low_y, high_y = table_bounds()
        for token, value, low, high in zip(tokens, values, (low_x, low_y), (high_x, high_y),
                                           strict=True):
            if not low <= value <= high:
                self.error("off-table", f"{what} at ({values[0]:g}, {values[1]:g}) can leave "
                           f"the table: it is beyond the table top (x in [{low_x:g}, "
                           f"{high_x:g}], y in [{low_y:g}, {high_y:g}])", token)
                return None
        return values[0], values[1]


def _shown(token: Token) -> str:
    """A number as written, shortened when it is long (as an overflow to infinity is)."""
    return str(token) if len(token) <= 24 else f"{token[:12]}...{token[-6:]} ({len(token)} " \
                                                "characters)"
