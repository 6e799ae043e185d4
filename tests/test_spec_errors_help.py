"""Errors in specs that help: each at the statement that causes it (file:line:col, the source
line and a caret), saying where and what, with 'did you mean' where a name is close; exit
status 1 through the CLI, never a traceback.

A case's text holds the marker « just before the character its error must point at."""

from __future__ import annotations

from pathlib import Path

import pytest

from robofollow import cli
from robofollow.benchmark.rounds import unknown_episode
from tests.spec_helpers import VALID, edit

MARK = "«"
TABLE = "(the table top: x in [-0.6, 0.6], y in [-0.4, 0.3])"
STATEMENTS = "point, object, fixture, jitter, set, layout, task, test, split"


def compile_spec(tmp_path: Path, text: str, capsys) -> tuple[int, str, str]:
    """Compile one spec file through the CLI: (exit status, stdout, stderr)."""
    folder = tmp_path / "specs"
    folder.mkdir()
    (folder / "bad.rf").write_text(text)
    status = cli.main(["compile", str(folder), "--out", str(tmp_path / "out"), "--no-verify"])
    captured = capsys.readouterr()
    assert "Traceback" not in captured.out + captured.err
    return status, captured.out, captured.err


def located(tmp_path: Path, marked: str, capsys) -> tuple[str, list[str]]:
    """The one error of a marked spec: its first line's prefix (file:line:col) and its lines."""
    at = marked.index(MARK)
    line = marked.count("\n", 0, at) + 1
    column = at - (marked.rfind("\n", 0, at) + 1) + 1
    status, _, err = compile_spec(tmp_path, marked.replace(MARK, ""), capsys)
    lines = err.splitlines()
    assert status == 1
    assert lines[-1] == "1 error in the specs", err
    assert lines[2] == "  " + " " * (column - 1) + lines[2].strip()  # the caret
    return f"{tmp_path / 'specs' / 'bad.rf'}:{line}:{column}: ", lines


def assert_error(tmp_path, marked, code, message, capsys) -> list[str]:
    where, lines = located(tmp_path, marked, capsys)
    assert lines[0] == f"{where}error[{code}]: {message}"
    return lines


def parse_hints(text: str, capsys) -> list[str]:
    """The hint lines `robofollow parse` prints under its caret."""
    assert cli.main(["parse", text]) == 1
    return capsys.readouterr().err.splitlines()[3:]


# ---------------------------------------------------------------- instructions


@pytest.mark.parametrize("text,bad,message", [
    ("Pick up the middel cube with your left arm.", "middel", "unknown word 'middel'"),
    ("Pick up the the red cube with your left arm.", "the red", "unexpected 'the' here"),
])
def test_an_instruction_in_a_spec_gets_the_hints_of_robofollow_parse(tmp_path, capsys, text,
                                                                     bad, message):
    hints = parse_hints(text, capsys)
    assert hints and hints[0].startswith(("  did you mean: 'middle'", "  expected: "))
    at = text.index(bad, 8)
    marked = edit('"Pick up the red cube with your left arm."',
                  f'"{text[:at]}{MARK}{text[at:]}"')
    kind = "unknown_word" if "unknown" in message else "ungrammatical"
    lines = assert_error(tmp_path, marked, f"instruction-{kind}", message, capsys)
    assert lines[3:-1] == hints


# ---------------------------------------------------------------- names


# (the text, its edit with {} for the misspelt name, the name, its kind, the name meant)
NAMES = [
    ("expect pick left red_cube", "expect pick left {}", "red_cub", "object", "red_cube"),
    ("blue_cube at p1", "blue_cube at {}", "p_1", "point", "p1"),
    ("blue_cube at p1", "blue_cube on {}", "red_cub", "object", "red_cube"),
    ("from base", "from {}", "bsae", "layout", "base"),
    ("swap red_cube blue_cube", "swap red_cube {}", "blu_cube", "object", "blue_cube"),
    ("task pick_red on base", "task pick_red on {}", "bsae", "layout in demo", "base"),
    ("layouts=(swapped)", "layouts=({})", "swaped", "layout", "swapped"),
    ("jitter * x=", "jitter {} x=", "bleu_cube", "object", "blue_cube"),
    ("layouts=(swapped)", "layouts=(swapped) wordings=({})", "referent", "wording",
     "referents"),
]
CODES = {"object": "unknown-object", "point": "unknown-point", "layout": "undefined-layout",
         "wording": "unknown-wording"}


@pytest.mark.parametrize("old,new,name,kind,meant", NAMES)
def test_an_unknown_name_suggests_a_declared_one(tmp_path, capsys, old, new, name, kind,
                                                 meant):
    kind, _, scene = kind.partition(" ")
    message = f"no {kind} named {name}{' ' + scene if scene else ''}; did you mean {meant!r}?"
    assert_error(tmp_path, edit(old, new.format(MARK + name)), CODES[kind], message, capsys)


def test_an_unknown_name_with_nothing_close_lists_the_known_ones(tmp_path, capsys):
    assert_error(tmp_path, edit("    jitter", f"    set {MARK}gravity = 9.8\n    jitter"),
                 "unknown-setting", "no setting named gravity (known: table_height, guess_margin)", capsys)


# ---------------------------------------------------------------- geometry


def test_an_overlap_in_a_base_layout_is_reported_once_at_its_statement(tmp_path, capsys):
    """The swap trades two cubes of one size: the derived layout keeps the overlap."""
    marked = edit("red_cube at (-0.1, 0.0)\n        blue_cube at p1",
                  f"red_cube at (0.08, 0.0)\n        {MARK}blue_cube at p1")
    assert_error(tmp_path, marked, "overlap", "blue_cube overlaps red_cube by 2.0 cm in "
                 "layout base (red_cube is placed on line 8); inherited by layout swapped",
                 capsys)


def test_an_overlap_a_derived_layout_makes_is_at_its_operation(tmp_path, capsys):
    marked = edit("    task pick_red", f"    layout moved from base {{ move {MARK}blue_cube "
                                       "to (-0.08, 0.0) }\n    task pick_red")
    assert_error(tmp_path, marked, "overlap", "blue_cube overlaps red_cube by 2.0 cm in "
                 "layout moved (red_cube is placed on line 8)", capsys)


def test_a_footprint_past_the_table_edge_is_measured(tmp_path, capsys):
    marked = edit("        bowl at (0.0, -0.15)", f"        {MARK}bowl at (0.58, -0.15)")
    assert_error(tmp_path, marked, "off-table", "bowl at (0.58, -0.15) reaches 3.0 cm past "
                 f"the table's edge in layout base {TABLE}; inherited by layout swapped",
                 capsys)


def test_a_jitter_that_carries_a_body_off_the_table_is_reported_at_the_jitter(tmp_path,
                                                                              capsys):
    marked = edit("bowl at (0.0, -0.15)", "bowl at (0.545, -0.15)").replace(
        "jitter * x=", f"jitter {MARK}* x=")
    assert_error(tmp_path, marked, "off-table", "the jitter of bowl can carry it 0.5 cm past "
                 f"the table's edge from (0.545, -0.15) in layout base {TABLE}; inherited by "
                 "layout swapped", capsys)


# ---------------------------------------------------------------- statements


@pytest.mark.parametrize("old,new,message", [
    ("swap red_cube blue_cube", f"{MARK}paint red_cube orange",
     ("unknown layout operation 'paint' (layout operations: at, on, in, swap, move, remove, "
     "put, recolor)")),
    ("swap red_cube blue_cube", f"{MARK}swp red_cube blue_cube",
     ("unknown layout operation 'swp'; did you mean 'swap'? (layout operations: at, on, in, "
     "swap, move, remove, put, recolor)")),
    ("    layout base", f"    {MARK}objet green_cube cube\n    layout base",
     (f"unknown statement 'objet'; did you mean 'object'? (a scene holds: {STATEMENTS}; an "
     "attribute is written name=value)")),
    ("    layout swapped", f"    {MARK}layot swapped",
     f"unknown statement 'layot'; did you mean 'layout'? (a scene holds: {STATEMENTS})"),
    ("expect pick", f"{MARK}expct pick",
     "unexpected expct; did you mean 'expect'? (expected: 'expect', '}', string)"),
])
def test_an_unknown_statement_is_named_as_such(tmp_path, capsys, old, new, message):
    assert_error(tmp_path, edit(old, new), "syntax", message, capsys)


@pytest.mark.parametrize("old,new,message", [
    ("cube half=0.02 color=red", f"cube {MARK}hlf=0.02 color=red",
     ("unknown attribute hlf here; did you mean 'half'? (expected one of: half, color, rgb, "
     "mass, friction)")),
    ("rounds=10 seed=42", f"{MARK}round=10 seed=42",
     ("unknown attribute round here; did you mean 'rounds'? (expected one of: layouts, "
     "wordings, max, rounds, seed, motion, repeats)")),
    ("jitter * x=", f"jitter * {MARK}z=", "unknown attribute z here (expected one of: x, y)"),
])
def test_an_unknown_attribute_is_one_error_with_a_suggestion(tmp_path, capsys, old, new,
                                                             message):
    assert_error(tmp_path, edit(old, new), "unknown-attribute", message, capsys)


# ---------------------------------------------------------------- layouts like training ones

LIKE_TRAINING = ("layout swapped looks the same as the training layout base (the same bodies "
                 "in the same places, up to bodies that look alike), so the L1 tasks on it "
                 "would not test a changed layout; change it, or write repeats=allowed on the "
                 "split rule if a distractor-free repeat is meant")


def test_a_layout_that_looks_like_a_training_one_is_an_error_at_the_layout(tmp_path, capsys):
    marked = edit("layout swapped from base { swap red_cube blue_cube }",
                  f"layout {MARK}swapped from base {{ }}")
    assert_error(tmp_path, marked, "looks-like-training", LIKE_TRAINING, capsys)


def test_a_split_rule_may_allow_a_repeat(tmp_path, capsys):
    text = edit("layout swapped from base { swap red_cube blue_cube }",
                "layout swapped from base { }").replace("seed=42", "seed=42 repeats=allowed")
    status, out, err = compile_spec(tmp_path, text, capsys)
    assert status == 0, err
    assert "yields no task" not in out
    assert "demo/L1/" in (tmp_path / "out" / "tasks" / "demo_L1.jsonl").read_text()


@pytest.mark.parametrize("old,new,code,message", [
    ("seed=42", f"seed=42 repeats={MARK}alowed", "bad-value",
     ("unknown repeats alowed; did you mean 'allowed'? (known: refused | allowed: a layout "
     "that looks the same as a training layout is an error, or a distractor-free repeat the "
     "rule means)")),
    ("    split L1", f"    split L2 {MARK}repeats=allowed\n    split L1", "unknown-attribute",
     "repeats applies to L1 and L3 (the levels on changed layouts), not to L2"),
])
def test_a_bad_repeats_value_is_located(tmp_path, capsys, old, new, code, message):
    assert_error(tmp_path, edit(old, new), code, message, capsys)


# ---------------------------------------------------------------- small ones


def test_the_summary_counts_agree_in_number(tmp_path, capsys):
    status, out, _ = compile_spec(tmp_path, VALID, capsys)
    assert status == 0
    assert out.startswith("RoboFollow: 1 scene, 1 training task, spec digest ")
    assert " over 1 training scene group (task labels" in out


def test_the_unknown_episode_hint_shows_an_id_of_the_benchmark():
    error = unknown_episode("demo/L1/nothing#r1", ["demo/L0/pick_red", "demo/L1/pick_red"])
    assert "(ids look like demo/L0/pick_red#r1)" in str(error)
    assert "scene1" not in str(error)


# ---------------------------------------------------------------- a broken training layout

ALONE = """    layout apart {
        red_cube at (0.1, 0.0)
        blue_cube at (-0.1, 0.0)
        bowl at (0.0, -0.15)
    }
    task pick_red"""


def test_a_typo_in_a_training_layout_beside_an_l1_layout_of_its_own_is_located(tmp_path,
                                                                               capsys):
    """An unknown body in the training layout, in a scene whose L1 rule names a layout not
    derived from it: the typo's error (it was a KeyError traceback: the layout that looks
    like a training one was sought among the layouts that could not be posed)."""
    marked = edit("        red_cube at (-0.1, 0.0)", f"        {MARK}red_cub at (-0.1, 0.0)")
    marked = marked.replace("    task pick_red", ALONE, 1).replace("layouts=(swapped)",
                                                                  "layouts=(apart)")
    assert_error(tmp_path, marked, "unknown-object",
                 "no object named red_cub; did you mean 'red_cube'?", capsys)


def test_an_error_in_a_layout_derived_from_a_broken_one_is_reported_with_it(tmp_path, capsys):
    """Every problem at once: the derived layout's own typo is reported beside its base's."""
    text = edit("        red_cube at (-0.1, 0.0)", "        red_cub at (-0.1, 0.0)").replace(
        "swap red_cube blue_cube", "swap red_cube blu_cube")
    status, _, err = compile_spec(tmp_path, text, capsys)
    assert status == 1 and err.splitlines()[-1] == "2 errors in the specs", err
    assert "no object named red_cub;" in err and "no object named blu_cube;" in err
