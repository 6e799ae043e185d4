"""Test tasks listed in a spec's levels (`test L3 name on layout { "..." expect ... }`):
compiled and audited like generated ones; what would stop a generated candidate is a spec
error at the test."""

from __future__ import annotations

from pathlib import Path

from robofollow.benchmark.pipeline import compile_specs
from robofollow.benchmark.rounds import all_episodes
from robofollow.cli import main
from robofollow.resources import builtin_specs

LEFT_BOWL = "Use your right arm to place the blue cylinder in the leftmost bowl."


def _spec(tmp_path: Path, tests: str) -> Path:
    """Scene 2's spec with `tests` added to the scene."""
    text = (builtin_specs() / "scene2.rf").read_text()
    end = text.rindex("}")
    folder = tmp_path / "specs"
    folder.mkdir()
    (folder / "scene2.rf").write_text(text[:end] + tests + text[end:])
    return folder


def test_listed_tests_compile_into_their_levels_with_episodes(tmp_path):
    folder = _spec(tmp_path, f'''
    test L3 left_bowl_swapped on scene2_5 {{
        "{LEFT_BOWL}"
        expect place right small_blue_cylinder in yellow_bowl
    }}
    test L1 blue_cylinder_swapped on scene2_5 {{
        "Pick up the smaller blue object using your left arm."
    }}
''')
    compiled = compile_specs(folder)
    listed = {t.id: t for t in compiled.splits.tasks if t.wording == "listed"}
    assert set(listed) == {"scene2/L3/left_bowl_swapped", "scene2/L1/blue_cylinder_swapped"}
    assert listed["scene2/L3/left_bowl_swapped"].behaviour.steps[0].target == "yellow_bowl"
    episodes = [e for e in all_episodes(compiled) if e.task == "scene2/L3/left_bowl_swapped"]
    assert len(episodes) == 10 and episodes[0].behaviour.steps[0].arm == "right"
    report = compiled.report
    assert all(not report[k] for k in ("leakage", "level_inconsistencies",
                                        "repertoire_violations", "ambiguities"))


def test_a_listed_test_obeys_the_rules_of_a_generated_one(tmp_path, capsys):
    folder = _spec(tmp_path, '''
    test L2 copied on default {
        "Use your left arm to pick up the red cylinder."
    }
    test L2 other_arm on default {
        "Use your right arm to pick up the red cylinder."
    }
''')
    assert main(["compile", str(folder), "--out", str(tmp_path / "build")]) == 1
    text = capsys.readouterr().err
    assert "scene2.rf:" in text and "test-leakage" in text and "its form is a training form" \
        in text
    assert "test-repertoire" in text and "pick right large_red_cylinder: no training step " \
        "moves alike" in text and "new arm: the right arm (trained: the left arm)" in text


def test_what_would_stop_a_candidate_is_an_error_at_the_test(tmp_path, capsys):
    folder = _spec(tmp_path, f'''
    test L3 wrong_bowl on scene2_5 {{
        "{LEFT_BOWL}"
        expect place right small_blue_cylinder in green_bowl
    }}
    test L2 which_cube on default {{
        "Use your left arm to pick up the cube."
    }}
''')
    assert main(["compile", str(folder), "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err
    assert "error[test-expectation]" in err and "the expectation says green_bowl" in err
    assert "error[test-ambiguous]" in err and "large_blue_cube, small_red_cube" in err
    assert "    test L3 wrong_bowl on scene2_5 {" in err and "^^^^^^^^^^" in err
    assert not (tmp_path / "out").exists()


def test_a_listed_instruction_that_does_not_parse_is_shown_with_a_caret(tmp_path, capsys):
    folder = _spec(tmp_path, """
    test L2 typo on default {
        "Use your left arm to pik up the cube."
    }
""")
    assert main(["compile", str(folder), "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err
    path = folder / "scene2.rf"
    line = next(i for i, text in enumerate(path.read_text().splitlines(), start=1)
                if "pik up" in text)
    assert f"{path}:{line}:31: error[instruction-unknown_word]" in err
    assert [line.strip() for line in err.splitlines()[-3:-1]] == ["^^^", "did you mean: 'pick'?"]
