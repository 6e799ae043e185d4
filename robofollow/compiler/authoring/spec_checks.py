"""The checks of what a spec writes that scenes and layouts share: each problem is a SpecError
at the place it is written; every number is finite and within its named limits (spec.py),
positions are on the table top, and an attribute is given once."""

from __future__ import annotations

import math
from collections.abc import Iterable

from lark import Token

from robofollow.compiler.authoring.spec_files import Sources, spec_error
from robofollow.compiler.authoring.spec_syntax import (
    Attribute,
    Coordinates,
    Number,
    Values,
)
from robofollow.compiler.language import lf
from robofollow.compiler.scene.spec import Source
from robofollow.compiler.scene.workspace import table_bounds
from robofollow.errors import SpecError, did_you_mean

_LISTED = 12  # the known names are listed when there are at most this many


class Checks:
    """Problems found so far, located in the file being read."""

    def __init__(self):
        self.errors: list[SpecError] = []
        self.sources = Sources()
        self.file = ""

    def error(self, code: str, message: str, where: Token | Source, length: int | None = None,
              hints: tuple[str, ...] = ()):
        """A problem at a place (a token: the length of the token is underlined)."""
        if isinstance(where, Token):
            where, length = self.source(where), length or len(where)
        self.errors.append(spec_error(code, message, where, self.sources, length or 1, hints))

    def unknown_name(self, code: str, kind: str, token: Token, known: Iterable[str],
                     where: str = "") -> None:
        """A name not among the `known` names of its kind (in declaration order): the close ones
        are suggested, or else a short list is shown whole."""
        known = list(known)
        hint = did_you_mean(str(token), known)
        if hint:
            hint = f"; {hint}"
        elif 0 < len(known) <= _LISTED:
            hint = f" (known: {', '.join(known)})"
        self.error(code, f"no {kind} named {token!s}{where}{hint}", token)

    def source(self, token: Token) -> Source:
        return Source(file=self.file, line=token.line, column=token.column)

    def attributes(self, nodes: tuple[Attribute, ...], allowed: tuple[str, ...]
                   ) -> dict[str, Attribute]:
        """The attributes given, by name; an unknown or repeated one is reported and left out."""
        found: dict[str, Attribute] = {}
        for node in nodes:
            key = node.key
            if key not in allowed:
                hint = did_you_mean(str(key), allowed)
                self.error("unknown-attribute", f"unknown attribute {key!s} here"
                           + (f"; {hint}" if hint else "")
                           + f" (expected one of: {', '.join(allowed)})", key)
            elif key in found:
                self.error("duplicate-attribute", f"{key!s} is given twice", key)
            else:
                found[str(key)] = node
        return found

    def colour(self, token: Token) -> str | None:
        """The colour word written at `token`, or None (reported there, with the colours)."""
        if token in lf.Color.__args__:
            return str(token)
        hint = did_you_mean(str(token), lf.Color.__args__)
        self.error("bad-value", f"unknown colour {token!s}" + (f"; {hint}" if hint else "")
                   + f" (colours: {', '.join(lf.Color.__args__)})", token)
        return None

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

    def number(self, node: Attribute, bounds: tuple[float, float], unit: str = "",
               whole: bool = False) -> float | None:
        """An attribute that takes one number (checked as `checked` does)."""
        if not isinstance(node.value, Number):
            self.error("bad-value", f"{node.key!s} takes a number", node.key)
            return None
        return self.checked(node.value.token, str(node.key), bounds, unit, whole)

    def numbers(self, node: Attribute, count: int, bounds: tuple[float, float],
                unit: str = "") -> tuple[float, ...] | None:
        """An attribute that takes `count` numbers: (a, b, c)."""
        key, value = node.key, node.value
        items = value.items if isinstance(value, Values) else (value,)
        if len(items) != count or not all(isinstance(i, Number) for i in items):
            self.error("bad-value", f"{key!s} takes {count} numbers in [{bounds[0]:g}, "
                       f"{bounds[1]:g}]{unit}: ({', '.join(['n'] * count)})", key)
            return None
        numbers = [self.checked(i.token, str(key), bounds, unit) for i in items]
        return None if None in numbers else tuple(numbers)

    def coordinates(self, node: Coordinates, what: str) -> tuple[float, float] | None:
        """(x, y) as written, or None (reported at the number) when a coordinate is not finite
        or the position is not on the table top."""
        tokens = (node.x, node.y)
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
