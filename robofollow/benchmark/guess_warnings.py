"""The guessable cells (`guessing.guessable`) as located warnings at their split rules: what
`compile` and `audit` print."""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from robofollow.compiler.authoring.spec_files import Sources, spec_error
from robofollow.compiler.scene.spec import Spec
from robofollow.errors import SpecError


def guess_warnings(spec: Spec, cells: Iterable[Mapping]) -> list[SpecError]:
    """Each guessable cell as a warning at its split rule, naming the layouts that make it so
    and the tests each one's guess answers."""
    warnings, sources = [], Sources()
    for cell in cells:
        rule = spec.scenes[cell["scene"]].splits[cell["level"]]
        over = cell["IS"] - cell["chance_IS"]
        hints = [f"layout {entry['layout']}: performing {entry['guess']} earns Intent "
                 f"{entry['guess_IS']:.1f} over its {entry['tests']} tests (chance "
                 f"{entry['chance_IS']:.1f}), at least half on {entry['earning']}"
                 + (": " + ", ".join(entry["earning_tests"]) if entry["earning"] else "")
                 + (", ..." if entry["earning"] > len(entry["earning_tests"]) else "")
                 for entry in cell["layouts"]]
        hints.append("add tests on these layouts that other training behaviours answer, or "
                     "raise the bound with `set guess_margin = N`")
        message = (f"{cell['scene']} {cell['level']} tells following from guessing poorly: the "
                   f"best language-blind guess earns Intent {cell['IS']:.1f}, {over:.1f} points "
                   f"over chance ({cell['chance_IS']:.1f}); the scene allows "
                   f"{cell['margin']:g}")
        warnings.append(spec_error("guessable", message, rule.source, sources,
                                   length=len(rule.level), hints=tuple(hints),
                                   severity="warning"))
    return warnings
