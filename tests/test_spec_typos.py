"""Typos anywhere in a scene with split rules: `robofollow compile` never raises past its own
errors. Each example takes a shipped spec whose L1 and L3 rules name layouts (or Scene 1 with
an L1 / L3 layout placed anew, not derived from the trained one), changes one
name, number or keyword of it outside its instructions and comments (a letter dropped, doubled,
swapped with the next or replaced) and compiles it; the build is clean, or every problem is
reported at its file, line and column (exit status 1), never a traceback. (Typos inside an
instruction are the parser's: tests/test_properties.py.)"""

from __future__ import annotations

import os
import re
import tempfile
from pathlib import Path
from unittest import mock

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from robofollow.cli import main
from robofollow.resources import builtin_specs

SHIPPED = {name: (builtin_specs() / name).read_text(encoding="utf-8")
           for name in ("scene1.rf", "scene2.rf")}  # split L1 / L3 layouts=(...) in both
APART = """    layout apart {
        red_sphere     at (0.10, -0.04)
        yellow_block_1 at (-0.02, -0.04)
        red_cylinder   at (-0.14, -0.04)
        yellow_block_2 at (0.10, -0.18)
        green_sphere   at (-0.02, -0.18)
        yellow_block_3 at (-0.14, -0.18)
    }
"""
SPECS = {**SHIPPED, "apart.rf": SHIPPED["scene1.rf"].replace(  # an L1 / L3 layout of its own,
    "    split L0", APART + "    split L0").replace(             # not derived from the trained
    "layouts=(scene1_1, scene1_2, scene1_3)", "layouts=(scene1_1, apart)")}  # one
RUNS = 300  # examples (the same ones every run)


def _tokens(text: str) -> list[tuple[int, int]]:
    """Where the names, numbers and keywords are, outside quoted text and comments."""
    blank = re.sub(r'"[^"\n]*"|#[^\n]*', lambda found: " " * len(found.group()), text)
    return [m.span() for m in re.finditer(r"[A-Za-z_][A-Za-z0-9_]*|\d+(?:\.\d+)?", blank)]


TOKENS = {name: _tokens(text) for name, text in SPECS.items()}


def _typo(word: str, how: str, at: int, letter: str) -> str:
    """`word` with one typo: a letter dropped, doubled, swapped with the next, or replaced."""
    at %= len(word)
    if how == "drop":
        return word[:at] + word[at + 1:]
    if how == "double":
        return word[:at + 1] + word[at:]
    if how == "swap" and at + 1 < len(word):
        return word[:at] + word[at + 1] + word[at] + word[at + 2:]
    return word[:at] + letter + word[at + 1:]


@settings(max_examples=RUNS, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])  # (capsys: read each time)
@given(data=st.data())
def test_a_typo_anywhere_is_a_located_error_or_a_clean_build(data, capsys):
    name = data.draw(st.sampled_from(sorted(SPECS)), label="spec")
    start, end = data.draw(st.sampled_from(TOKENS[name]), label="token")
    text = SPECS[name]
    word = _typo(text[start:end], data.draw(st.sampled_from(["drop", "double", "swap",
                                                             "replace"]), label="typo"),
                 data.draw(st.integers(0, 40), label="at"),
                 data.draw(st.sampled_from("aeioustx_1"), label="letter"))
    with tempfile.TemporaryDirectory() as folder, \
            mock.patch.dict(os.environ, {"ROBOFOLLOW_NO_CACHE": "1"}):
        spec = Path(folder) / "specs" / name
        spec.parent.mkdir()
        spec.write_text(text[:start] + word + text[end:], encoding="utf-8")
        status = main(["compile", str(spec.parent), "--out", str(Path(folder) / "build"),
                       "--no-verify"])
    out, err = capsys.readouterr()
    assert status in (0, 1), err
    assert "Traceback" not in out + err
    if status == 1 and "error" in err:
        assert re.search(rf"{re.escape(str(spec))}:\d+:\d+: error", err), err
