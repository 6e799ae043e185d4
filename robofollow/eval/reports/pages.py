"""The jinja environment of the run reports and comparisons (templates/), and the number
formats their tables share.

Every HTML template (`*.html.j2`) escapes what it shows: run records hold text from policies
and policy servers (error messages), which must never become markup. No template marks a
value |safe. The markdown templates pass such text through md_text or md_code."""

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


def md_text(value) -> str:
    """Outside text (a run's folder name, a policy's error, a path) as one line of markdown
    that carries no markup: line breaks become spaces, and < and > entities, so no renderer
    reads a tag into it."""
    text = " ".join(str(value).splitlines())
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def md_code(value) -> str:
    """Outside text as a markdown code span, fenced with more backticks than it holds (so it
    cannot close the span early) and on one line."""
    text = " ".join(str(value).splitlines())
    longest = max((len(run) for run in text.replace("`", " ` ").split() if set(run) == {"`"}),
                  default=0)
    fence = "`" * (longest + 1)
    padded = f" {text} " if text.startswith("`") or text.endswith("`") else text
    return f"{fence}{padded}{fence}"


PAGES.globals.update(interval=interval, signed_interval=signed_interval, p_value=p_value,
                     rounds_of=rounds_of, shade=shade)
PAGES.filters.update(md_text=md_text, md_code=md_code)


def signed(value: float) -> str:
    """A difference in points with its sign: '+1.5'."""
    return f"{value:+.1f}"
