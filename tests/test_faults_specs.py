"""Malformed specs and bad output folders: `robofollow compile` ends with exit status 1 and one
clear message at the right place, never a traceback, a hang or a half-written build.

Each spec case writes a spec with the marker « just before the character its error must point
at; the marker is removed, and the error must be reported at exactly that file:line:column
(with the source line and a caret under it), as the only error of the run (no cascade), and
nothing may be written to --out.
"""

from __future__ import annotations

import errno
import json
import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from robofollow import cli
from robofollow.benchmark import output
from robofollow.compiler.scene.spec import (
    MAX_BODIES,
    MAX_LAYOUTS,
    MAX_SPEC_BYTES,
    MAX_STACK,
)
from tests.spec_helpers import VALID

MARK = "«"
BIG = "9" * 400  # a number that overflows to infinity
SECRET = "top secret first line"


@dataclass
class Case:
    id: str
    code: str
    text: str | bytes | None = None  # bad.rf, with the marker
    extra: dict | None = None  # other files: name -> text; or a setup function
    setup: object = None  # folder -> (file, line, column) for cases that are not text


def edit(old: str, new: str, code: str, case_id: str, base: str = VALID) -> Case:
    assert base.count(old) >= 1, old
    return Case(case_id, code, base.replace(old, new, 1))


def numbers() -> list[Case]:
    """Non-finite, huge and out-of-range numbers in every numeric position."""
    at, bowl, point = "red_cube at (-0.1, 0.0)", "bowl at (0.0, -0.15)", "point p1 (0.1, 0.0)"
    half, mass = "cube half=0.02 color=red", "rgb=(1, 0, 0) mass=0.2"
    friction, rgb = "mass=0.2 friction=0.1", "rgb=(1, 0, 0)"
    jitter, split = "jitter * x=[-0.01, 0.01] y=[-0.01, 0.01]", "split L1 layouts=(swapped)"
    rounds, expect = "rounds=10 seed=42", "expect pick left red_cube"
    swap, setting = "swap red_cube blue_cube", "    jitter *"
    place = "expect place left red_cube on blue_cube yaw "
    cases = [
        (at, f"red_cube at ({MARK}{BIG}, 0.0)", "bad-value", "at-x-inf"),
        (at, f"red_cube at (-0.1, {MARK}-{BIG})", "bad-value", "at-y-minus-inf"),
        (at, f"red_cube at ({MARK}1000000000, 0.0)", "off-table", "at-x-huge"),
        (at, f"red_cube at (-0.1, {MARK}-1000000000)", "off-table", "at-y-huge"),
        (bowl, f"bowl at ({MARK}0.7, -0.15)", "off-table", "at-just-off-the-table"),
        (point, f"point p1 ({MARK}{BIG}, 0.0)", "bad-value", "point-x-inf"),
        (point, f"point p1 (0.1, {MARK}5)", "off-table", "point-y-off-table"),
        (swap, f"move red_cube to (0.1, {MARK}{BIG})", "bad-value", "move-y-inf"),
        (swap, f"move red_cube to ({MARK}-2, 0.1)", "off-table", "move-x-off-table"),
        (half, f"cube half={MARK}{BIG} color=red", "bad-value", "half-inf"),
        (half, f"cube half={MARK}5 color=red", "bad-value", "half-huge"),
        (half, f"cube half={MARK}0.0001 color=red", "bad-value", "half-tiny"),
        ("bowl radius=0.05", f"bowl radius={MARK}{BIG}", "bad-value", "radius-inf"),
        ("half_height=0.02", f"half_height={MARK}1000", "bad-value", "half-height-huge"),
        (bowl, "bowl at (0.0, -0.15)\n        pad at (0.2, -0.2)", "bad-value",
         "label-half-inf"),
        (mass, f"rgb=(1, 0, 0) mass={MARK}{BIG}", "bad-value", "mass-inf"),
        (mass, f"rgb=(1, 0, 0) mass={MARK}0", "bad-value", "mass-zero"),
        (mass, f"rgb=(1, 0, 0) mass={MARK}1000", "bad-value", "mass-huge"),
        (mass, f"rgb=(1, 0, 0) mass={MARK}-1", "bad-value", "mass-negative"),
        (friction, f"mass=0.2 friction={MARK}{BIG}", "bad-value", "friction-inf"),
        (friction, f"mass=0.2 friction={MARK}0", "bad-value", "friction-zero"),
        (friction, f"mass=0.2 friction={MARK}100", "bad-value", "friction-huge"),
        (rgb, f"rgb=(1, {MARK}{BIG}, 0)", "bad-value", "rgb-inf"),
        (rgb, f"rgb=(1, 0, {MARK}2)", "bad-value", "rgb-above-one"),
        (rgb, f"rgb=({MARK}-1, 0, 0)", "bad-value", "rgb-negative"),
        (rgb, f"{MARK}rgb=(1, 0)", "bad-value", "rgb-two-numbers"),
        (rgb, f"{MARK}rgb=((1, 0), 0, 0)", "bad-value", "rgb-nested"),
        (jitter, f"jitter * x=[{MARK}-{BIG}, 0.01] y=[-0.01, 0.01]", "bad-value",
         "jitter-minus-inf"),
        (jitter, f"jitter * x=[-0.01, {MARK}100] y=[-0.01, 0.01]", "bad-value", "jitter-100m"),
        (jitter, f"jitter * x=[{MARK}-0.5, 0.01] y=[-0.01, 0.01]", "bad-value",
         "jitter-beyond-table-fraction"),
        (jitter, f"jitter * x=[-0.01, 0.01] y=[-0.01, {MARK}{BIG}]", "bad-value", "jitter-y-inf"),
        (jitter, f"jitter * {MARK}x=[0.01, -0.01] y=[-0.01, 0.01]", "bad-value",
         "jitter-inverted"),
        (jitter, f"jitter * {MARK}x=0.5 y=[-0.01, 0.01]", "bad-value", "jitter-not-interval"),
        (jitter, f"{jitter}\n    jitter red_cube x=[{MARK}-1, 0.01]", "bad-value",
         "jitter-of-one-body"),
        (setting, f"    set table_height = {MARK}-5\n    jitter *", "bad-value",
         "table-height-negative"),
        (setting, f"    set table_height = {MARK}{BIG}\n    jitter *", "bad-value",
         "table-height-inf"),
        (setting, f"    set table_height = {MARK}5\n    jitter *", "bad-value",
         "table-height-huge"),
        (setting, f"    set {MARK}table_height = high\n    jitter *", "bad-value",
         "table-height-name"),
        (expect, f"{place}{MARK}{BIG}", "bad-value", "yaw-inf"),
        (expect, f"{place}{MARK}1000", "bad-value", "yaw-huge"),
        (expect, f"{place}{MARK}-720", "bad-value", "yaw-negative-huge"),
        (rounds, f"rounds={MARK}0 seed=42", "bad-value", "rounds-zero"),
        (rounds, f"rounds={MARK}1000000000 seed=42", "bad-value", "rounds-billion"),
        (rounds, f"rounds={MARK}{BIG} seed=42", "bad-value", "rounds-inf"),
        (rounds, f"rounds={MARK}2.5 seed=42", "bad-value", "rounds-fraction"),
        (split, f"{split} max={MARK}0", "bad-value", "max-zero"),
        (split, f"{split} max={MARK}100000", "bad-value", "max-huge"),
        (split, f"{split} max={MARK}{BIG}", "bad-value", "max-inf"),
        (rounds, f"rounds=10 seed={MARK}-1", "bad-value", "seed-negative"),
        (rounds, f"rounds=10 seed={MARK}{BIG}", "bad-value", "seed-inf"),
        (rounds, f"rounds=10 seed={MARK}3000000000", "bad-value", "seed-huge"),
        (rounds, f"rounds=10 seed={MARK}1.5", "bad-value", "seed-fraction"),
        (at, f"red_cube at (1{MARK}e9, 0.0)", "syntax", "exponent-is-not-a-number"),
    ]
    result = [edit(old, new, code, case_id) for old, new, code, case_id in cases]
    label = next(case for case in result if case.id == "label-half-inf")
    label.text = label.text.replace("    jitter *", f"    fixture pad label half=(0.03, 0.03, "
                                    f"{MARK}{BIG}) color=green rgb=(0, 1, 0)\n    jitter *")
    return result


def structure() -> list[Case]:
    """Deep derivations, tall stacks, duplicates, unknown names, empty files."""
    base = "    layout swapped from base { swap red_cube blue_cube }"
    chain = [base] + [f"    layout {MARK if i == MAX_LAYOUTS - 2 else ''}d{i} from "
                      f"{'swapped' if i == 0 else f'd{i - 1}'} {{ }}" for i in range(3000)]
    cubes = "\n".join(f"    object {MARK if i == MAX_BODIES - 3 else ''}c{i} cube half=0.001 "
                      "color=red rgb=(1, 0, 0) mass=0.2 friction=0.1" for i in range(1500))
    stacked = "\n".join(f"        c{i} on c{i - 1}" for i in range(1, 1500))
    tall = "\n".join(f"    object c{i} cube half=0.005 color=red rgb=(1, 0, 0) mass=0.2 "
                     "friction=0.1" for i in range(MAX_STACK + 1))
    tall_stack = "\n".join(f"        {MARK if i == MAX_STACK else ''}c{i} on c{i - 1}"
                           for i in range(1, MAX_STACK + 1))
    task = ('    task pick_red on base {\n        "Pick up the red cube with your left arm."\n'
            "        expect pick left red_cube\n    }\n")
    listed = ('    test L0 {}t1 on base {{\n        "Pick up the red cube with your left arm."\n'
              '    }}\n')
    cases = [
        (base, "\n".join(chain), "too-many-layouts", "3000-derived-layouts"),
        (base, ("    layout swapped from base { swap red_cube blue_cube }\n"
               f"    layout {MARK}a from c {{ }}\n    layout b from a {{ }}\n"
               "    layout c from b { }"), "layout-cycle", "derivation-cycle"),
        ("    jitter *", cubes + "\n    jitter *", "too-many-bodies", "1500-bodies"),
        ("    jitter *", cubes + "\n    jitter *", "too-many-bodies", "1500-body-stack"),
        ("    layout base {\n        red_cube", (f"{tall}\n    layout base {{\n"
         f"        c0 at (0.2, -0.2)\n{tall_stack}\n        red_cube"), "stack-too-tall",
         "stack-taller-than-the-limit"),
        ("        bowl at (0.0, -0.15)", ("        bowl at (0.0, -0.15)\n        red_cube on bowl\n"
         f"        bowl on blue_cube\n        {MARK}blue_cube on red_cube"), "support-cycle",
         "support-cycle-of-three"),
        ("    object blue_cube", (f"    object {MARK}red_cube sphere radius=0.02 color=red "
         "rgb=(1, 0, 0) mass=0.2 friction=0.1\n    object blue_cube"), "duplicate-object",
         "duplicate-object"),
        (base, f"{base}\n    layout {MARK}swapped {{ red_cube at (0.1, 0.1) }}",
         "duplicate-layout", "duplicate-layout"),
        ("point p1 (0.1, 0.0)", f"point p1 (0.1, 0.0)\n    point {MARK}p1 (0.2, 0.0)",
         "duplicate-point", "duplicate-point"),
        ("split L1", f"split L0 rounds=10\n    split {MARK}L0", "duplicate-split",
         "duplicate-split"),
        ("cube half=0.02 color=red", f"cube half=0.02 {MARK}half=0.03 color=red",
         "duplicate-attribute", "duplicate-attribute"),
        ("    layout base", f"    jitter {MARK}* x=[-0.01, 0.01]\n    layout base",
         "duplicate-jitter", "duplicate-jitter"),
        ("    jitter *", (f"    set table_height = 0.74\n    set {MARK}table_height = 0.75\n"
         "    jitter *"), "duplicate-setting", "duplicate-setting"),
        ("    split", listed.format("") + listed.format(MARK) + "    split", "duplicate-test",
         "duplicate-test"),
        ("cube half=0.02 color=red", f"cube half=0.02 {MARK}colour=red color=red",
         "unknown-attribute", "unknown-attribute"),
        ("    jitter *", f"    set {MARK}gravity = 9.8\n    jitter *", "unknown-setting",
         "unknown-setting"),
        ("object red_cube cube half=0.02", f"object red_cube {MARK}pyramid radius=0.02",
         "unknown-kind", "unknown-kind-with-other-sizes"),
        ("layouts=(swapped)", f"layouts=(swapped) wordings=({MARK}rhymes)", "unknown-wording",
         "unknown-wording"),
        ("layouts=(swapped)", f"{MARK}layouts=(1, 2)", "bad-value", "layouts-as-numbers"),
        ("color=red rgb", f"color={MARK}crimson rgb", "bad-value", "bad-colour-no-cascade"),
        (task, "", "no-tasks", "scene-without-tasks"),
    ]
    result = [edit(old, new, code, case_id) for old, new, code, case_id in cases]
    result[-1].text = result[-1].text.replace("scene demo", f"scene {MARK}demo")
    result[3].text = result[3].text.replace(
        "        bowl at (0.0, -0.15)", f"        bowl at (0.0, -0.15)\n        c0 at (0.2, -0.2)"
        f"\n{stacked}", 1)
    other = VALID.replace("scene demo", "scene other").replace("pick_red", "pick_other")
    result += [
        Case("empty-file", "empty-spec", f"{MARK}"),
        Case("comments-only", "empty-spec", f"{MARK}# nothing here yet\n\n# still nothing\n"),
        Case("duplicate-scene-in-two-files", "duplicate-scene",
             VALID.replace("scene demo", f"scene {MARK}demo").replace("pick_red", "pick_b"),
             {"a.rf": VALID}),
        Case("duplicate-label-in-two-files", "duplicate-label",
             other.replace("task pick_other", f"task {MARK}pick_red"), {"a.rf": VALID}),
    ]
    return result


def files() -> list[Case]:
    """What is not a regular spec file, and bytes that are not UTF-8."""
    def fifo(folder: Path):
        os.mkfifo(folder / "pipe.rf")
        return folder / "pipe.rf", 1, 1

    def link_out(folder: Path):
        outside = folder.parent / "outside.txt"
        outside.write_text(SECRET + "\n")
        (folder / "link.rf").symlink_to(outside)
        return folder / "link.rf", 1, 1

    def directory(folder: Path):
        (folder / "sub.rf").mkdir()
        return folder / "sub.rf", 1, 1

    def too_big(folder: Path):
        (folder / "big.rf").write_text("# " + "x" * MAX_SPEC_BYTES + "\n")
        return folder / "big.rf", 1, 1

    text = VALID.encode()
    line9 = b"        blue_cube at p1  # caf\xc3\xa9 "
    bad = text.replace(b"        blue_cube at p1", line9 + MARK.encode() + b"\xff", 1)
    cut = text.replace(b"        bowl at (0.0, -0.15)",
                       b"        bowl at (0.0, -0.15)  # " + MARK.encode() + b"\xe2\x82", 1)
    return [
        Case("fifo", "unreadable", extra={"a.rf": VALID}, setup=fifo),
        Case("symlink-out-of-the-folder", "unreadable", extra={"a.rf": VALID}, setup=link_out),
        Case("folder-named-rf", "unreadable", extra={"a.rf": VALID}, setup=directory),
        Case("file-too-big", "unreadable", extra={"a.rf": VALID}, setup=too_big),
        Case("bad-utf8-mid-file", "encoding", bad),
        Case("cut-utf8-sequence", "encoding", cut),
        Case("latin1-on-the-first-line", "encoding",
             b"# " + MARK.encode() + b"\xe9t\xe9\n" + text),
    ]


CASES = numbers() + structure() + files()


def make(folder: Path, case: Case) -> tuple[Path, int, int]:
    """Write the case's files; where its error must be: (file, line, column)."""
    folder.mkdir()
    for name, text in (case.extra or {}).items():
        (folder / name).write_text(text)
    if case.setup is not None:
        return case.setup(folder)
    data = case.text.encode() if isinstance(case.text, str) else case.text
    mark = MARK.encode()
    assert data.count(mark) == 1, case.id
    at = data.index(mark)
    line = data.count(b"\n", 0, at) + 1
    column = len(data[data.rfind(b"\n", 0, at) + 1:at].decode("utf-8")) + 1
    (folder / "bad.rf").write_bytes(data.replace(mark, b""))
    return folder / "bad.rf", line, column


def test_there_are_at_least_sixty_cases():
    assert len(CASES) >= 60
    assert len({case.id for case in CASES}) == len(CASES)


@pytest.mark.parametrize("case_id,line,column", [
    ("at-x-inf", 8, 22), ("jitter-100m", 6, 24), ("rounds-billion", 17, 39),
    ("scene-without-tasks", 1, 7), ("bad-utf8-mid-file", 9, 33), ("cut-utf8-sequence", 10, 33),
    ("3000-derived-layouts", 267, 12), ("1500-bodies", 67, 12)])
def test_the_marker_is_where_a_person_counts(case_id, line, column, tmp_path):
    """The marker's place, counted by hand for a few cases (columns count characters)."""
    case = next(c for c in CASES if c.id == case_id)
    assert make(tmp_path / "specs", case)[1:] == (line, column)


@pytest.mark.parametrize("case", CASES, ids=[case.id for case in CASES])
def test_a_malformed_spec_is_one_error_at_its_place(case, tmp_path, capsys):
    file, line, column = make(tmp_path / "specs", case)
    out = tmp_path / "out"
    status = cli.main(["compile", str(tmp_path / "specs"), "--out", str(out)])
    captured = capsys.readouterr()
    assert status == 1, captured.out + captured.err
    assert "Traceback" not in captured.out + captured.err
    lines = captured.err.splitlines()
    assert lines[0].startswith(f"{file}:{line}:{column}: error[{case.code}]: "), lines[0]
    assert lines[-1] == "1 error in the specs", captured.err  # no cascade
    if len(lines) > 2:  # the source line, and a caret under the column
        assert lines[2] == "  " + " " * (column - 1) + "^" * (len(lines[2]) - column - 1)
    assert SECRET not in captured.err
    assert not out.exists()


@pytest.mark.slow  # a process each (the import alone takes a second or two)
@pytest.mark.parametrize("case_id", ["fifo", "at-x-inf", "empty-file", "1500-body-stack",
                                     "symlink-out-of-the-folder"])
def test_the_real_exit_status(case_id, tmp_path):
    case = next(c for c in CASES if c.id == case_id)
    file, line, column = make(tmp_path / "specs", case)
    result = subprocess.run([sys.executable, "-m", "robofollow.cli", "compile",
                             str(tmp_path / "specs"), "--out", str(tmp_path / "out")],
                            check=False, capture_output=True, text=True, timeout=120)
    assert result.returncode == 1
    assert result.stderr.startswith(f"{file}:{line}:{column}: error[{case.code}]")
    assert "Traceback" not in result.stderr and SECRET not in result.stderr
    assert not (tmp_path / "out").exists()


def test_the_symlink_message_says_why_without_reading_the_target(tmp_path, capsys):
    make(tmp_path / "specs", next(c for c in CASES if c.id == "symlink-out-of-the-folder"))
    assert cli.main(["compile", str(tmp_path / "specs"), "--out", str(tmp_path / "o")]) == 1
    assert "symbolic link that leads out of the spec folder" in capsys.readouterr().err


def test_a_long_chain_of_derived_layouts_within_the_limit_loads(tmp_path):
    from robofollow.compiler.authoring.spec_loader import load_spec

    chain = "\n".join(f"    layout d{i} from {'swapped' if i == 0 else f'd{i - 1}'} {{ }}"
                      for i in range(MAX_LAYOUTS - 2))
    text = VALID.replace("    task pick_red", chain + "\n    task pick_red")
    (tmp_path / "a.rf").write_text(text)
    spec = load_spec(tmp_path)
    assert len(spec.scenes["demo"].layouts) == MAX_LAYOUTS


def test_a_stack_at_the_limit_loads_and_poses_without_recursion(tmp_path):
    from robofollow.compiler.authoring.spec_loader import load_spec
    from robofollow.compiler.scene.world import World

    bodies = "\n".join(f"    object c{i} cube half=0.005 color=red rgb=(1, 0, 0) mass=0.2 "
                       "friction=0.1" for i in range(MAX_STACK))
    stack = "\n".join(f"        c{i} on c{i - 1}" for i in range(1, MAX_STACK))
    text = VALID.replace("    jitter *", bodies + "\n    jitter *").replace(
        "        bowl at (0.0, -0.15)", f"        bowl at (0.0, -0.15)\n        c0 at (0.2, "
        f"-0.2)\n{stack}")
    (tmp_path / "a.rf").write_text(text)
    scene = load_spec(tmp_path).scenes["demo"]
    top = scene.layouts["base"].placed[f"c{MAX_STACK - 1}"]
    assert top.z == pytest.approx(scene.table_height + 0.005 * (2 * MAX_STACK - 1))
    # World walks a stack in a loop: a layout made by hand far beyond the limit still poses
    placed = dict(scene.layouts["base"].placed)
    for i in range(MAX_STACK, 3000):
        placed[f"c{i}"] = placed["c1"].model_copy(update={"support": f"c{i - 1}"})
    bodies = {**scene.bodies, **{f"c{i}": scene.bodies["c0"] for i in range(MAX_STACK, 3000)}}
    layout = scene.layouts["base"].model_copy(update={"placed": placed})
    huge = scene.model_copy(update={"layouts": {"base": layout}, "bodies": bodies})
    assert World(huge, "base", {"c0": (0.01, 0.0)}).poses["c2999"].x == pytest.approx(0.21)


# ------------------------------------------------------------------ --out


def compile_to(out: Path, specs: Path, capsys) -> tuple[int, str, str]:
    status = cli.main(["compile", str(specs), "--out", str(out)])
    captured = capsys.readouterr()
    assert "Traceback" not in captured.out + captured.err
    return status, captured.out, captured.err


@pytest.fixture
def specs(tmp_path) -> Path:
    folder = tmp_path / "specs"
    folder.mkdir()
    (folder / "demo.rf").write_text(VALID)
    return folder


def leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if ".partial-" in p.name or ".old-" in p.name)


def test_out_refuses_a_folder_that_is_not_a_build(tmp_path, specs, capsys):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("keep me")
    status, _, err = compile_to(out, specs, capsys)
    assert status == 1 and "is not empty and does not hold a previous build" in err
    assert sorted(os.listdir(out)) == ["notes.txt"]


def test_out_replaces_a_previous_build_whole_and_reports_the_changes(tmp_path, specs, capsys):
    out = tmp_path / "build"
    assert compile_to(out, specs, capsys)[0] == 0
    (out / "episodes" / "gone_L0.jsonl").write_text("")  # a scene the specs no longer have
    (out / "tasks" / "gone_L0.jsonl").write_text(json.dumps({"task": "gone/L0/t"}) + "\n")
    status, printed, _ = compile_to(out, specs, capsys)
    assert status == 0
    assert "against the previous build: 0 test tasks added, 1 removed" in printed
    assert "  - gone/L0/t" in printed
    assert not (out / "episodes" / "gone_L0.jsonl").exists()
    assert sorted(os.listdir(out / "episodes")) == [f"demo_{lv}.jsonl" for lv in
                                                     ("L0", "L1", "L2", "L3")]
    assert leftovers(tmp_path) == []


def test_out_creates_missing_parents(tmp_path, specs, capsys):
    out = tmp_path / "a" / "b" / "build"
    assert compile_to(out, specs, capsys)[0] == 0
    assert (out / "summary.txt").is_file()


@pytest.mark.parametrize("where,message", [
    ("file", "is a file, not a folder"),
    ("below-a-file", "is a file, not a folder"),
])
def test_out_that_is_or_passes_through_a_file(tmp_path, specs, capsys, where, message):
    (tmp_path / "afile").write_text("x")
    out = tmp_path / "afile" if where == "file" else tmp_path / "afile" / "sub" / "build"
    status, _, err = compile_to(out, specs, capsys)
    assert status == 1 and message in err
    assert (tmp_path / "afile").read_text() == "x"


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_out_in_a_read_only_folder(tmp_path, specs, capsys):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o555)
    try:
        status, _, err = compile_to(locked / "build", specs, capsys)
        assert status == 1 and "is read-only" in err
    finally:
        locked.chmod(0o755)


def test_out_read_only_as_the_check_sees_it(tmp_path, specs, capsys, monkeypatch):
    """The same refusal where permissions are not enforced (root): os.access says no."""
    monkeypatch.setattr(output.os, "access", lambda path, mode: False)
    status, _, err = compile_to(tmp_path / "build", specs, capsys)
    assert status == 1 and f"--out {tmp_path / 'build'} cannot be made: {tmp_path} is " \
                           "read-only" in err
    assert not (tmp_path / "build").exists()


def test_a_full_disk_leaves_the_previous_build_and_nothing_half_written(tmp_path, specs,
                                                                        capsys, monkeypatch):
    out = tmp_path / "build"
    assert compile_to(out, specs, capsys)[0] == 0
    before = {p.relative_to(out): p.read_bytes() for p in out.rglob("*") if p.is_file()}
    written = output._write_files

    def full(compiled, folder, summary, files):  # the disk fills up part-way through
        written(compiled, folder, summary, dict(list(files.items())[:3]))
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(output, "_write_files", full)
    status, _, err = compile_to(out, specs, capsys)
    assert status == 1
    assert f"cannot write the build to {out}: no space left on the device" in err
    assert {p.relative_to(out): p.read_bytes() for p in out.rglob("*") if p.is_file()} == before
    assert leftovers(tmp_path) == []


def test_a_full_disk_on_a_new_folder_leaves_nothing(tmp_path, specs, capsys, monkeypatch):
    def full(compiled, folder, summary, files):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(output, "_write_files", full)
    status, _, err = compile_to(tmp_path / "new" / "build", specs, capsys)
    assert status == 1 and "no space left on the device" in err
    assert not (tmp_path / "new").exists()
