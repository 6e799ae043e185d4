"""The jinja environment of the run reports and comparisons (templates/), and the number
formats their tables share.

Every HTML template (`*.html.j2`) escapes what it shows: run records hold text from policies
and policy servers (error messages), which must never become markup. No template marks a
value |safe."""

from __future__ import annotations

import math

import jinja2

PAGES = jinja2.Environment(
    loader=jinja2.PackageLoader("robofollow.eval.reports", "templates"),
    autoescape=jinja2.select_autoescape(["html", "html.j2"], default_for_string=True,
                                        default=False),
    trim_blocks=True, lstrip_blocks=True, undefined=jinja2.StrictUndefined)


def interval(bounds: list[float] | None) -> str:
    """An interval as the reports print it ('n/a': a cell of one task has no task interval)."""
    return "n/a" if bounds is None else f"{bounds[0]:.1f}–{bounds[1]:.1f}"


def signed_interval(bounds: list[float] | None) -> str:
    """An interval of a difference as the tables print it."""
    return "[n/a]" if bounds is None else f"[{bounds[0]:+.1f}, {bounds[1]:+.1f}]"


def p_value(value: float) -> str:
    """A p-value as the tables print it."""
    return f"{value:.3g}" if value >= 0.001 else "< 0.001"


def rounds_of(cell: dict) -> str:
    """Episodes per task in a cell (a whole number when every task ran as often)."""
    rounds = cell["episodes"] / max(cell["tasks"], 1)
    return f"{rounds:.0f}" if rounds == int(rounds) else f"{rounds:.1f}"


def shade(value: float) -> str:
    """Table 1's background for an Intent (0-100): green on a square-root scale, so that
    0-30, where learned policies sit, spreads over half of it."""
    light = round(255 - 150 * math.sqrt(max(0.0, min(value, 100.0)) / 100))
    return f"rgb({light}, 255, {light})" if value > 0 else "#fff"


PAGES.globals.update(interval=interval, signed_interval=signed_interval, p_value=p_value,
                     rounds_of=rounds_of, shade=shade)


def signed(value: float) -> str:
    """A difference in points with its sign: '+1.5'."""
    return f"{value:+.1f}"
