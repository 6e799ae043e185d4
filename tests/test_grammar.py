"""The grammar file, the lexicon and the packaged wheel agree."""

import subprocess
import sys
import zipfile

import pytest

from robofollow.compiler.language.lexicon import TERMINALS, VOCABULARY
from robofollow.resources import grammar_text


def test_grammar_declares_exactly_the_lexicon_terminals():
    declared = set()
    for line in grammar_text("instruction.lark").splitlines():
        if line.startswith("%declare"):
            declared.update(line.split()[1:])
    assert declared == TERMINALS


def test_every_terminal_has_words():
    used = {entry.terminal for entry in VOCABULARY.values()}
    assert TERMINALS - used == {"AND_MOD", "AND_NP", "PLEASE_END", "NOT_GOING", "COMMA",
                                "SEMICOLON", "PERIOD"}


def test_grammar_is_conflict_free_lalr():
    from robofollow.compiler.language.parser import _lark
    parser = _lark()  # built with strict=True: any LALR conflict raises
    assert parser.options.parser == "lalr" and parser.options.strict


@pytest.mark.slow
def test_wheel_ships_the_grammar_and_parses_when_installed(tmp_path):
    root = __import__("pathlib").Path(__file__).resolve().parent.parent
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
                    "-w", str(tmp_path / "dist"), str(root)], check=True, capture_output=True)
    wheel = next((tmp_path / "dist").glob("robofollow-*.whl"))
    names = zipfile.ZipFile(wheel).namelist()
    assert "robofollow/grammar/instruction.lark" in names
    assert "robofollow/compiler/language/templates/english.j2" in names
    assert "robofollow/sim/templates/scene.xml.j2" in names
    assert {f"robofollow/specs/scene{i}.rf" for i in range(1, 5)} <= set(names)
    assert {"robofollow/baselines/scene2-text/policy.json",
            "robofollow/baselines/scene2-text/params.npz"} <= set(names)
    assert {"robofollow/releases/v1/manifest.json",
            "robofollow/releases/v1/benchmark.jsonl.gz"} <= set(names)
    target = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "--target",
                    str(target), str(wheel)], check=True, capture_output=True)
    code = ("import robofollow, sys; from robofollow.compiler.language.parser import parse; "
            "from robofollow.resources import builtin_specs; "
            "assert builtin_specs().is_relative_to(robofollow.__path__[0]); "
            "from robofollow import release; frozen = release.load(); "
            "assert len(frozen.ids) == release.manifest(frozen.release).episodes; "
            "print(robofollow.__file__); print(parse('Pick up the red cube.').object.noun)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            cwd=tmp_path, env={"PYTHONPATH": str(target), "PATH": ""})
    assert result.returncode == 0, result.stderr
    location, noun = result.stdout.split()
    assert location.startswith(str(target)) and noun == "cube"
