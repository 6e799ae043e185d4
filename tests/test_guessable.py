"""The compile's check of discrimination: a cell whose best language-blind guess rises more than
the scene's `guess_margin` over chance is warned about at its split rule, naming the layouts and
tests that make it guessable; `--strict` fails the build on it; the margin is a checked
setting that decides no split."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from robofollow import cli
from robofollow.benchmark.pipeline import compile_specs

SCENE1 = Path(__file__).resolve().parent.parent / "specs" / "scene1.rf"
HEADER = 'scene scene1 "Extrinsic spatial relations" {\n'


def _specs(tmp_path: Path, setting: str = "") -> Path:
    """Scene 1 alone in a folder, with `setting` as its first statement."""
    folder = tmp_path / "specs"
    folder.mkdir()
    text = SCENE1.read_text(encoding="utf-8")
    assert text.count(HEADER) == 1
    (folder / "scene1.rf").write_text(text.replace(HEADER, HEADER + setting), encoding="utf-8")
    return folder


def _compile(tmp_path: Path, specs: Path, *extra: str) -> int:
    return cli.main(["compile", str(specs), "--out", str(tmp_path / "out"), "--no-verify",
                     *extra])


def _split_line(specs: Path, level: str) -> tuple[int, str]:
    """The line number and text of the scene's split rule for `level`."""
    lines = (specs / "scene1.rf").read_text(encoding="utf-8").splitlines()
    number = next(i for i, line in enumerate(lines, 1) if line.strip().startswith(f"split {level}"))
    return number, lines[number - 1]


def test_a_guessable_cell_is_warned_at_its_split_rule_with_its_layouts_and_tests(tmp_path,
                                                                                   capsys):
    specs = _specs(tmp_path)
    assert _compile(tmp_path, specs) == 0  # a warning stops nothing without --strict
    err = capsys.readouterr().err
    line, text = _split_line(specs, "L1")
    column = text.index("L1") + 1
    assert (f"scene1.rf:{line}:{column}: warning[guessable]: scene1 L1 tells following from "
            "guessing poorly") in err
    assert f"  {text}\n  {' ' * (column - 1)}^^\n" in err
    # the layout whose guess earns most, the guess, and a test it earns on
    assert ("layout scene1_2: performing place_yellow_block_3_behind_red_cylinder earns Intent "
            in err)
    assert "scene1/L1/place_yellow_block_1_behind_red_cylinder@scene1_2" in err
    assert "set guess_margin = N" in err
    audit = json.loads((tmp_path / "out" / "audit.json").read_text())
    flagged = {(cell["scene"], cell["level"]) for cell in audit["guessable"]}
    assert flagged == {("scene1", "L1"), ("scene1", "L3")}
    for cell in audit["guessable"]:
        assert cell["IS"] - cell["chance_IS"] > cell["margin"] == 15
        assert all(entry["guess_IS"] > entry["chance_IS"] for entry in cell["layouts"])


def test_strict_fails_the_build_on_a_guessable_cell(tmp_path, capsys):
    assert _compile(tmp_path, _specs(tmp_path), "--strict") == 1
    assert "--strict: 2 warnings fail the build" in capsys.readouterr().out


def test_a_wider_margin_passes_strict_and_changes_no_split(tmp_path, capsys):
    plain, wide = tmp_path / "plain", tmp_path / "wide"
    plain.mkdir()
    wide.mkdir()
    assert _compile(wide, _specs(wide, "    set guess_margin = 50\n"), "--strict") == 0
    assert "warning[guessable]" not in capsys.readouterr().err
    assert _compile(plain, _specs(plain)) == 0
    for name in ("tasks", "episodes"):
        for path in (plain / "out" / name).iterdir():
            assert (wide / "out" / name / path.name).read_bytes() == path.read_bytes()
    ours = compile_specs(wide / "specs")
    assert ours.spec.scenes["scene1"].guess_margin == 50.0
    assert ours.report["guessable"] == []


@pytest.mark.parametrize(("value", "column", "said"), [
    ("120", 24, "guess_margin = 120 is out of range: it must be in [0, 100] Intent points"),
    ("-1", 24, "guess_margin = -1 is out of range: it must be in [0, 100] Intent points"),
    ("1" + "0" * 400, 24, "is not a finite number; it must be in [0, 100] Intent points"),
    ("nan", 9, "guess_margin takes a number"),
])
def test_the_margin_is_a_checked_setting(tmp_path, capsys, value, column, said):
    specs = _specs(tmp_path, f"    set guess_margin = {value}\n")
    assert _compile(tmp_path, specs) == 1
    err = capsys.readouterr().err
    assert f"scene1.rf:5:{column}: error[bad-value]: " in err and said in err


def test_every_cell_reports_its_chance_beside_its_best_guess():
    best = compile_specs(SCENE1.parent).report["blind_best"]
    for levels in best.values():
        for cell in levels.values():
            for metric in ("IS", "CR"):  # (each kept to one decimal)
                assert 0.0 <= cell[f"chance_{metric}"] and cell[metric] <= 100.0
                assert cell[f"chance_{metric}"] - cell[metric] <= 0.1 + 1e-9
            assert [entry["layout"] for entry in cell["layouts"]]
