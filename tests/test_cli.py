"""`robofollow parse` from the command line."""

import io
import json
import subprocess
import sys

from tests.cli_helpers import run


def test_parse_prints_form_and_english(capsys):
    status, out, _ = run(capsys, "parse", "Grab the leftmost cube with your left arm.")
    assert status == 0
    assert out.splitlines() == ["lf       pick(left, cube[leftmost])",
                                "english  Use your left arm to pick up the leftmost cube."]


def test_parse_json_is_the_canonical_form(capsys):
    status, out, _ = run(capsys, "parse", "--json", "Push the red cube towards the bowl.")
    assert status == 0
    data = json.loads(out)
    assert data["type"] == "push" and data["toward"] == {"noun": "bowl", "constraints": []}


def test_parse_error_shows_caret_and_suggestion_and_exits_1(capsys):
    status, out, err = run(capsys, "parse", "Pick up the blue cilinder.")
    assert status == 1 and out == ""
    assert err.splitlines()[:3] == ["error: unknown word 'cilinder' (column 18)",
                                    "  Pick up the blue cilinder.",
                                    "  " + " " * 17 + "^" * 8]
    assert "did you mean: 'cylinder'" in err


def test_parse_stdin_writes_json_lines_and_exits_1_on_any_failure(capsys, monkeypatch):
    monkeypatch.setattr(sys, "stdin", io.StringIO(
        "Pick up the red cube.\n\nPlace it behind.\nPick up the ball.\n"))
    status, out, _ = run(capsys, "parse", "-")
    records = [json.loads(line) for line in out.splitlines()]
    assert status == 1
    assert [r["text"] for r in records] == ["Pick up the red cube.", "", "Place it behind.",
                                            "Pick up the ball."]  # one answer per line
    assert records[0]["lf"]["object"]["noun"] == "cube"
    assert records[1]["error"]["message"] == "the instruction is empty"
    assert records[2]["error"] == {"type": "ungrammatical", "column": 16,
                                   "message": "the instruction ends too early"}
    assert records[3]["lf"]["object"]["noun"] == "sphere"


def test_parse_stdin_splits_records_at_newlines_only():
    text = "Pick up the\rcube.\r\nPick up the ball\u2028now.\n"
    result = subprocess.run(["robofollow", "parse", "-"], input=text.encode(),
                            capture_output=True)
    lines = result.stdout.split(b"\n")[:-1]
    assert len(lines) == 2 and b"\xe2\x80\xa8" not in result.stdout  # U+2028 escaped
    records = [json.loads(line) for line in lines]
    assert records[0]["text"] == "Pick up the\rcube." and records[0]["lf"]["type"] == "pick"
    assert records[1]["text"] == "Pick up the ball\u2028now."


def test_parse_stdin_all_good_exits_0(capsys, monkeypatch):
    monkeypatch.setattr(sys, "stdin", io.StringIO("Pick up the red cube.\n"))
    assert run(capsys, "parse", "-")[0] == 0


def test_console_script_help():
    result = subprocess.run(["robofollow", "parse", "--help"], capture_output=True, text=True)
    assert result.returncode == 0
    assert "robofollow parse -" in result.stdout and "--json" in result.stdout


def test_parse_stdin_survives_bytes_that_are_not_utf8():
    result = subprocess.run(["robofollow", "parse", "-"], input=b"Pick up the cube.\n\xff\xfe\n",
                            capture_output=True)
    records = [json.loads(line) for line in result.stdout.decode().splitlines()]
    assert result.returncode == 1 and result.stderr == b""
    assert records[0]["lf"]["type"] == "pick"
    assert records[1]["error"]["type"] == "unknown_word"


def test_a_command_outside_the_repository_uses_the_built_in_specs_and_says_so(tmp_path):
    result = subprocess.run(["robofollow", "audit"], cwd=tmp_path, capture_output=True,
                            text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert result.stderr.startswith("specs: the built-in benchmark (")
    assert "4 scenes, 75 training tasks" in result.stdout
    (tmp_path / "specs").mkdir()  # a specs/ folder here is this folder's benchmark
    result = subprocess.run(["robofollow", "audit"], cwd=tmp_path, capture_output=True,
                            text=True, timeout=300)
    assert result.returncode == 1 and "specs: ./specs" in result.stderr
    assert "Traceback" not in result.stderr
