"""The one JSON Lines reader every caller uses: numbered lines, what is wrong and where."""

from __future__ import annotations

from robofollow.files import json_line, json_lines


def test_lines_are_numbered_split_at_newlines_only_and_blank_ones_passed_over():
    data = (json_line({"a": "x\u2028y"}) + "\n  \n" + json_line([1, 2])).encode()
    lines = list(json_lines(data))
    assert [(line.number, line.value, line.problem) for line in lines] == [
        (1, {"a": "x\u2028y"}, None), (4, [1, 2], None)]


def test_a_line_that_is_not_utf8_is_placed_at_its_character():
    data = '{"é": 1}\n'.encode() + b'{"k": "\xff"}\n'
    [line] = [line for line in json_lines(data) if line.problem]
    assert (line.number, line.column, line.text) == (2, 8, False)
    assert line.problem == "not UTF-8 text (byte 0xff)"


def test_a_line_that_is_not_json_says_why_and_where():
    [line] = [line for line in json_lines(b'{"ok": true}\n{"ok": tru}\n') if line.problem]
    assert (line.number, line.column, line.text) == (2, 8, True)
    assert line.problem.startswith("not JSON (Expecting value")
