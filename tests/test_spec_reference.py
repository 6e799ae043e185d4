"""docs/spec-language.md stays the complete reference of the spec language: every keyword and
terminal of grammar/spec.lark, every kind, attribute, colour, setting, relation, arm and split
option the loader accepts, every wording generator, level, task rule and named limit (with its
value), and every option of `robofollow compile` appears on that page, in its section.

The lists are read from the code: the grammar with lark, the loader's tables, and, where the
loader writes a list inline (the attributes of `jitter` and `split`), the list its
unknown-attribute error names."""

from __future__ import annotations

import re
from functools import cache
from pathlib import Path

import pytest
from lark import Lark

from robofollow.audit.task_list import FINDING_KINDS
from robofollow.cli import parser as cli_parser
from robofollow.compiler.authoring import spec_loader, spec_splits
from robofollow.compiler.authoring.spec_loader import load_partial
from robofollow.compiler.language import lf
from robofollow.compiler.scene import spec, workspace
from robofollow.compiler.splits.task_rules import _GROUNDED_RULES
from robofollow.compiler.splits.wordings import GENERATORS
from robofollow.resources import builtin_specs, grammar_text

DOC = Path(__file__).resolve().parent.parent / "docs" / "spec-language.md"

# grammar rule -> the section of the page whose code must show its literals (a rule missing here
# fails the test: a new statement needs its place on the page and here)
SECTIONS = {
    "start": "Lexical rules", "_item": "Lexical rules", "attribute": "Lexical rules",
    "value": "Lexical rules", "coordinates": "Lexical rules", "position": "`layout`",
    "scene": "`scene`", "setting": "`set`", "point": "`point`", "body": "`object`",
    "body_kind": "`object`", "jitter": "`jitter`", "layout": "`layout`",
    "layout_op": "`layout`", "rgb": "`layout`", "task": "`task`", "test": "`test`", "expect": "`expect`",
    "branch": "`expect`", "step": "`expect`", "relation": "`expect`", "waypoint": "`expect`",
    "yaw": "`expect`", "split": "`split`",
}


@cache
def _doc() -> str:
    return DOC.read_text(encoding="utf-8")


def _section(title: str) -> str:
    """The text of the section whose heading starts with `title` (with its subsections)."""
    lines = _doc().splitlines()
    for index, line in enumerate(lines):
        match = re.match(r"(#+) (.*)", line)
        if match and match.group(2).startswith(title):
            depth, body = len(match.group(1)), []
            for following in lines[index + 1:]:
                heading = re.match(r"(#+) ", following)
                if heading and len(heading.group(1)) <= depth:
                    break
                body.append(following)
            return "\n".join(body)
    raise AssertionError(f"{DOC.name} has no section {title!r}")


def _code(text: str) -> str:
    """What a text shows as code: its fenced blocks and inline `code` spans."""
    fenced = re.findall(r"```[^\n]*\n(.*?)```", text, re.DOTALL)
    rest = re.sub(r"```[^\n]*\n.*?```", "", text, flags=re.DOTALL)
    return "\n".join(fenced + re.findall(r"`([^`\n]+)`", rest))


def _shows(text: str, word: str) -> bool:
    """Whether `word` appears as code in `text`: a whole word (or the literal, for
    punctuation)."""
    code = _code(text)
    if re.fullmatch(r"\w+", word):
        return re.search(rf"(?<![\w-]){re.escape(word)}(?![\w-])", code) is not None
    return word in code


def _missing(title: str, words, rows: bool = False) -> list[str]:
    """The words a section does not show as code (with `rows`: in none of its table rows)."""
    section = _section(title)
    if rows:
        section = "\n".join(line for line in section.splitlines() if line.startswith("|"))
    return sorted(word for word in set(words) if not _shows(section, word))


# ---------------------------------------------------------------- the grammar
@cache
def _grammar() -> Lark:
    return Lark(grammar_text("spec.lark"), parser="lalr")


def _literals_by_rule() -> dict[str, set[str]]:
    """Each grammar rule's string literals (lark's helper rules counted with their rule)."""
    grammar = _grammar()
    found: dict[str, set[str]] = {}
    for rule in grammar.rules:
        name = re.sub(r"^__(.*)_(star|plus)_\d+$", r"\1", str(rule.origin.name))
        for symbol in rule.expansion:
            if symbol.is_term:
                pattern = grammar.get_terminal(symbol.name).pattern
                if pattern.type == "str":
                    found.setdefault(name, set()).add(pattern.value)
        found.setdefault(name, set())
    return found


def test_every_grammar_rule_has_its_section():
    assert sorted(set(_literals_by_rule()) - set(SECTIONS)) == []


@pytest.mark.parametrize("rule", sorted(SECTIONS))
def test_every_literal_of_the_grammar_is_shown_in_its_section(rule):
    literals = _literals_by_rule().get(rule, set())
    assert _missing(SECTIONS[rule], literals) == []


def test_every_named_terminal_is_described_in_the_lexical_rules():
    named = re.findall(r"^([A-Z][A-Z_]*)\s*:", grammar_text("spec.lark"), re.MULTILINE)
    assert named and _missing("Lexical rules", named) == []


# ---------------------------------------------------------------- what the loader accepts
def _unknown_attribute_lists(text: str, tmp_path: Path) -> list[list[str]]:
    """The allowed attributes each unknown-attribute error of a spec names, in order."""
    path = tmp_path / "probe.rf"
    path.write_text(text, encoding="utf-8")
    lists = []
    for error in load_partial(path).errors:
        match = re.search(r"expected one of: ([^)]*)\)", error.message)
        if error.code == "unknown-attribute" and match:
            lists.append(match.group(1).split(", "))
    return lists


def test_every_body_kind_and_its_attributes(tmp_path):
    kinds = list(spec_loader._SIZES)
    assert set(kinds) == set(spec.BodyKind.__args__)
    lines = [f"object o_{kind} {kind} zzz=1" for kind in kinds]
    lines += [f"fixture f_{kind} {kind} zzz=1" for kind in kinds]
    lists = _unknown_attribute_lists(
        "scene probe \"probe\" {\n" + "\n".join(lines) + "\n}\n", tmp_path)
    assert len(lists) == 2 * len(kinds)
    attributes = {a for names in lists for a in names}
    assert {"mass", "friction", "color", "rgb"} <= attributes
    assert _missing("`object`", kinds, rows=True) == []
    assert _missing("`object`", attributes, rows=True) == []


def test_every_colour():
    assert _missing("`object`", lf.Color.__args__) == []


def test_every_setting_with_its_default():
    assert _missing("`set`", spec_loader._SETTINGS, rows=True) == []
    for name, default in spec_loader._SETTINGS.items():
        row = next(line for line in _section("`set`").splitlines() if f"`{name}`" in line)
        assert f"{default:g}" in row


def test_every_jitter_attribute(tmp_path):
    lists = _unknown_attribute_lists(
        "scene probe \"probe\" {\n    jitter * zzz=[0, 0]\n}\n", tmp_path)
    assert lists and _missing("`jitter`", lists[0]) == []


def test_every_split_option_with_its_values(tmp_path):
    lists = _unknown_attribute_lists(
        "scene probe \"probe\" {\n    split L1 zzz=1\n}\n", tmp_path)
    assert lists and "motion" in lists[0]
    assert _missing("`split`", lists[0], rows=True) == []
    assert _missing("`split`", spec.SPLIT_MOTIONS) == []
    assert _missing("`split`", spec.MOTION_LEVELS) == []


def test_every_relation_arm_and_branch_of_expect():
    assert _missing("`expect`", lf.PlaceRelation.__args__) == []
    assert _missing("`expect`", lf.Arm.__args__) == []


def test_every_wording_generator():
    assert set(spec_splits.WORDINGS) == set(GENERATORS)
    assert _missing("Wording generators", spec_splits.WORDINGS) == []
    table = "\n".join(line for line in _section("Wording generators").splitlines()
                      if line.startswith("| `"))
    assert all(f"| `{name}` |" in table for name in GENERATORS)


def test_every_level_and_task_rule():
    assert _missing("Levels and how the splits are made", spec.LEVELS) == []
    kinds = set(FINDING_KINDS) | {kind for kind, _ in _GROUNDED_RULES}
    assert _missing("Levels and how the splits are made", kinds) == []


def test_every_compile_option():
    commands = next(a for a in cli_parser()._actions if hasattr(a, "choices") and a.choices
                    and "compile" in a.choices)
    options = {o for a in commands.choices["compile"]._actions for o in a.option_strings
               if o.startswith("--") and o != "--help"}
    assert options and _missing("`splits.lock`", options) == []


# ---------------------------------------------------------------- the limits, with their values
def _numbers(value) -> list[str]:
    values = value if isinstance(value, tuple) else (value,)
    return [str(v) if isinstance(v, int) else f"{v:g}" for v in values]


def _limits() -> dict[str, object]:
    """spec.py's named numbers and ranges, and the table's geometry from workspace.py."""
    named = {name: value for name, value in vars(spec).items()
             if name.isupper() and (isinstance(value, (int, float)) or (
                 isinstance(value, tuple) and value
                 and all(isinstance(v, (int, float)) for v in value)))}
    named.update(TABLE_SIZE=workspace.TABLE_SIZE, TABLE_CENTRE_Y=workspace.TABLE_CENTRE_Y)
    return named


@pytest.mark.parametrize("name", sorted(_limits()))
def test_every_limit_is_listed_with_its_value(name):
    rows = [line for line in _section("Limits").splitlines() if line.startswith(f"| `{name}` |")]
    assert rows, f"no row for {name} in the Limits table"
    shown = re.split(r"\s*\|\s*", rows[0])[2]
    for number in _numbers(_limits()[name]):
        assert re.search(rf"(?<![\d.]){re.escape(number)}(?![\d.])", shown), (name, number)


_CODE = re.compile(r'(?:\.error|\.warning|Error|unknown_name|spec_error|SpecError)\(\s*'
                   r'"([a-z][a-z0-9-]+)"')  # an error's code, written where it is raised


def test_every_error_code_the_compiler_raises_is_in_the_error_table():
    """The codes written as literals where the compiler raises its errors (grounding's
    `unsupported` was missing) are each in the page's table of codes by statement."""
    source = Path(spec.__file__).resolve().parents[1]
    codes = {code for path in source.rglob("*.py") for code in _CODE.findall(path.read_text())}
    table = _doc()[_doc().index("| statement | codes |"):]
    table = table[:table.index("\n\n")]
    assert len(codes) > 30
    assert sorted(code for code in codes if f"`{code}`" not in table) == []


# ---------------------------------------------------------------- the words the rewordings use

STYLE_WORDS = re.compile(r"<!-- style words -->\n(.*?)\n<!-- /style words -->", re.S)
DESCRIBED = {"COLOR", "NOUN", "NOUNS", "SIZE", "EXTREME"}  # (the scene's bodies: its own words)


def _style_words() -> str:
    """The table docs/spec-language.md gives: per kind of instruction, the words the four
    styles say the shipped training tasks' forms with, beyond the bodies' descriptions."""
    from robofollow.compiler.language.realize import STYLES, realize
    from robofollow.compiler.splits.wordings import concepts

    loaded = load_partial(builtin_specs())
    words: dict[str, set[str]] = {}
    for task in loaded.spec.tasks:
        for style in sorted(STYLES):
            words.setdefault(task.forms[0].type, set()).update(
                value for kind, value in concepts(realize(task.forms[0], style))
                if kind not in DESCRIBED)
    rows = ["| instruction | words the styles use (beyond colours, sizes, nouns, extremes) |",
            "|---|---|"]
    rows += [f"| {kind} | {', '.join(sorted(found))} |" for kind, found in sorted(words.items())]
    return "\n".join(rows)


def test_the_docs_list_the_words_the_rewordings_use():
    found = STYLE_WORDS.search(_doc())
    assert found, "docs/spec-language.md has no <!-- style words --> table"
    assert found.group(1) == _style_words(), "\n" + _style_words()
