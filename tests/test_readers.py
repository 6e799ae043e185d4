"""Every result file is read through one validating reader: a bad file is a RoboFollowError on
one line that names the file, the line (where the file has lines) and the field; never a
traceback, a NaN or out-of-range number in a table, or a huge allocation. Valid files read as
they did before."""

from __future__ import annotations

import csv
import gzip
import io
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from robofollow.errors import RoboFollowError
from robofollow.eval.running import scores
from robofollow.eval.running.run_folder import (
    CorruptResultsError,
    read_results,
    summarised_episodes,
)
from robofollow.eval.running.saved_run import load_options
from robofollow.eval.running.scores import compact_records, read_scores
from tests.cli_helpers import run as run_cli
from tests.report_helpers import fake_record

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "docs" / "results"
BLIND = RESULTS / "blind"
BASELINES = ROOT / "robofollow" / "baselines"


def _one_line(error: BaseException | str, *parts: str) -> str:
    """The error's message, checked to be one line holding every part."""
    text = str(error)
    assert "\n" not in text, text
    for part in parts:
        assert part in text, (part, text)
    return text


def _refused(call, *parts: str, kind: type[Exception] = RoboFollowError) -> str:
    with pytest.raises(kind) as caught:
        call()
    return _one_line(caught.value, *parts)


# -- RUN/scores.csv.gz -------------------------------------------------------------------------

def _old_read_scores(path: Path) -> list[dict]:
    """read_scores as it was before it checked anything (what valid files must still read
    to)."""
    rows = list(csv.DictReader(io.StringIO(gzip.decompress(path.read_bytes()).decode())))
    return [dict(row, intent=float(row["intent"]), execution=float(row["execution"]),
                 complete=row["complete"] == "1", start=row.get("start", "")) for row in rows]


def _csv_lines(path: Path) -> list[list[str]]:
    return list(csv.reader(io.StringIO(gzip.decompress(path.read_bytes()).decode())))


def _write_csv(path: Path, lines: list[list[str]]) -> Path:
    text = io.StringIO()
    csv.writer(text, lineterminator="\n").writerows(lines)
    path.write_bytes(gzip.compress(text.getvalue().encode(), mtime=0))
    return path


@pytest.fixture(scope="module")
def blind_lines() -> list[list[str]]:
    """The shipped blind run's scores file: its header and first five rows."""
    return _csv_lines(BLIND / "scores.csv.gz")[:6]


def _changed(tmp_path: Path, lines: list[list[str]], line: int, column: str, value: str
             ) -> Path:
    """The scores file with `column` of (1-based) `line` set to `value`."""
    lines = [list(fields) for fields in lines]
    lines[line - 1][lines[0].index(column)] = value
    return _write_csv(tmp_path / "scores.csv.gz", lines)


def test_the_shipped_scores_read_as_before_and_a_changed_row_is_refused(tmp_path):
    shipped = BLIND / "scores.csv.gz"
    rows = read_scores(shipped)
    assert rows == _old_read_scores(shipped)
    assert [list(row) for row in rows] == [list(row) for row in _old_read_scores(shipped)]
    assert len(rows) == 6350 and compact_records(rows) == compact_records(
        _old_read_scores(shipped))
    lines = _csv_lines(shipped)
    lines[100][lines[0].index("intent")] = "500"
    copy = _write_csv(tmp_path / "scores.csv.gz", lines)
    _refused(lambda: read_scores(copy), str(copy), "line 101", "intent", "500")


@pytest.mark.parametrize("line, column, value, says", [
    (3, "intent", "abc", 'intent is "abc", not a number'),
    (3, "intent", "500", "intent is 500, not a number from 0 to 1"),
    (4, "intent", "nan", "intent is NaN, not a finite number"),
    (2, "execution", "-0.1", "execution is -0.1, not a number from 0 to 1"),
    (2, "execution", "inf", "execution is Infinity, not a finite number"),
    (5, "complete", "2", 'complete is "2", not one of "0", "1"'),
    (2, "seed", "x1", 'seed is "x1", not a whole number from 0'),
    (2, "seed", "1.5", 'seed is "1.5", not a whole number'),
    (3, "clipped", "-1", 'clipped is "-1", not a whole number'),
    (3, "steps", "ten", 'steps is "ten", not a whole number'),
    (2, "chance_is", "2", "chance_is is 2, not a number from 0 to 1"),
    (2, "chance_cr", "", "chance_is and chance_cr: one is empty"),
    (6, "followed", "1.5", "followed is 1.5, not a number from 0 to 1"),
    (2, "motion", "sideways", 'motion is "sideways", not one of'),
    (3, "episode", "scene1/L9/pickup#r1", 'episode names the level "L9", not one of L0, L1'),
    (3, "episode", "Scene 1/L0/pickup#r1", 'episode names the scene "Scene 1"'),
    (3, "episode", "scene1-L0-pickup",
     'episode is "scene1-L0-pickup", not an episode id (scene/level/label#rN)'),
    (3, "episode", "scene1/L0/pickup#r0", 'episode ends in "#r0", not a round'),
])
def test_a_bad_value_in_a_scores_file_names_its_line_and_column(tmp_path, blind_lines, line,
                                                                column, value, says):
    path = _changed(tmp_path, blind_lines, line, column, value)
    _refused(lambda: read_scores(path), f"{path}: line {line}: {says}")


def test_a_repeated_episode_or_a_short_row_in_a_scores_file_is_refused(tmp_path, blind_lines):
    path = _write_csv(tmp_path / "scores.csv.gz", [*blind_lines, blind_lines[2]])
    _refused(lambda: read_scores(path), f"{path}: line 7: episode", "is also on line 3")
    path = _write_csv(tmp_path / "scores.csv.gz", [*blind_lines, blind_lines[3][:-2]])
    _refused(lambda: read_scores(path), f"{path}: line 7: 21 fields, but the header names 23")


@pytest.mark.parametrize("header, says", [
    (lambda h: [("intnet" if n == "intent" else n) for n in h],
     "line 1: unknown column \"intnet\"; did you mean 'intent'?"),
    (lambda h: [n for n in h if n != "clipped"] + ["clipped"], None),  # any order is fine
    (lambda h: [n for n in h if n != "steps"], "line 1: lacks the columns steps"),
    (lambda h: h[:5] + ["intent"] + h[6:], "line 1: the column intent appears twice"),
])
def test_a_scores_header_is_checked(tmp_path, blind_lines, header, says):
    names = header(blind_lines[0])
    lines = [names] + [[dict(zip(blind_lines[0], fields, strict=True)).get(name, "")
                        for name in names] for fields in blind_lines[1:]]
    path = _write_csv(tmp_path / "scores.csv.gz", lines)
    if says is None:
        assert read_scores(path)[0]["clipped"] == blind_lines[1][blind_lines[0].index("clipped")]
        lines[2][names.index("clipped")] = "-3"  # (and still checked where it stands)
        path = _write_csv(tmp_path / "scores.csv.gz", lines)
        _refused(lambda: read_scores(path), f"{path}: line 3: clipped")
    else:
        _refused(lambda: read_scores(path), f"{path}: {says}")


def test_a_scores_file_that_is_not_utf8_names_its_line_and_column(tmp_path, blind_lines):
    text = io.StringIO()
    csv.writer(text, lineterminator="\n").writerows(blind_lines)
    data = text.getvalue().encode().replace(b"Use your", b"Use \xffyour", 1)
    path = tmp_path / "scores.csv.gz"
    path.write_bytes(gzip.compress(data))
    _refused(lambda: read_scores(path), f"{path}: line 2, column", "not UTF-8 text (byte 0xff)")


def test_a_scores_file_that_unpacks_past_the_cap_is_refused_without_reading_it_all(tmp_path):
    assert scores.MAX_UNPACKED >= 16 * 3_009_127  # far above the largest shipped one
    path = tmp_path / "scores.csv.gz"
    chunk = b"0" * (1 << 20)
    with gzip.open(path, "wb") as f:
        for _ in range((scores.MAX_UNPACKED >> 20) + 2):
            f.write(chunk)
    assert path.stat().st_size < 1 << 20  # small packed
    _refused(lambda: read_scores(path), str(path), "unpacks to more than 64 MiB")


def test_the_shipped_scores_files_are_all_valid():
    shipped = sorted(RESULTS.glob("**/scores.csv.gz"))
    assert len(shipped) >= 10
    for path in shipped:  # each far under the cap, valid, and read as before
        assert len(gzip.decompress(path.read_bytes())) < scores.MAX_UNPACKED / 16
        assert read_scores(path) == _old_read_scores(path)
        assert scores.holds_reported(path)


def _copied_run(tmp_path: Path, name: str = "blind", source: Path = BLIND) -> Path:
    folder = tmp_path / name
    folder.mkdir()
    for file in ("run.json", "summary.json", "scores.csv.gz"):
        shutil.copy(source / file, folder / file)
    return folder


def _damage_scores(run: Path, line: int, column: str, value: str) -> None:
    lines = _csv_lines(run / "scores.csv.gz")
    lines[line - 1][lines[0].index(column)] = value
    _write_csv(run / "scores.csv.gz", lines)


def _cli_error(capsys, *argv: str) -> str:
    status, _, err = run_cli(capsys, *argv)
    assert status == 1 and "Traceback" not in err, err
    assert err.count("\n") == 1, err  # one line
    return err


def test_report_and_compare_stop_at_a_bad_scores_file_with_one_line(tmp_path, capsys):
    run, other = _copied_run(tmp_path), _copied_run(tmp_path, "noop", RESULTS / "noop")
    _damage_scores(run, 5, "seed", "twelve")
    path = run / "scores.csv.gz"
    says = f'error: {path}: line 5: seed is "twelve", not a whole number from 0'
    assert _cli_error(capsys, "report", str(run)).startswith(says)
    assert _cli_error(capsys, "compare", str(run), str(other)).startswith(says)
    _damage_scores(run, 5, "seed", "745")
    _damage_scores(run, 9, "intent", "500")  # (a table would show IS 326.0)
    assert "line 9: intent is 500" in _cli_error(capsys, "report", str(run))


# -- RUN/run.json ----------------------------------------------------------------------------

PROVENANCE = [{"robofollow": "0.9.0", "commit": None, "python": "3.11.7", "numpy": "2.4.6",
               "mujoco": "3.3.0", "jax": None, "cpu": "some CPU", "platform": "linux-x86_64"}]


def _run_json(tmp_path: Path, change) -> Path:
    folder = _copied_run(tmp_path)
    data = json.loads((folder / "run.json").read_text())
    (folder / "run.json").write_text(change(data) if callable(change) else change)
    return folder


def _with(**changes):
    return lambda data: json.dumps({**data, **changes})


def _without(key: str):
    return lambda data: json.dumps({k: v for k, v in data.items() if k != key})


def test_run_json_with_provenance_reads_its_options_and_environments(tmp_path):
    from robofollow.eval.running.saved_run import load_provenance

    shipped = load_options(BLIND)
    folder = _run_json(tmp_path, _with(provenance=PROVENANCE))
    assert load_options(folder) == shipped and shipped.rounds == 10
    assert load_provenance(folder) == PROVENANCE
    assert load_provenance(BLIND) == []  # recorded before runs recorded one
    assert load_provenance(tmp_path / "nothing") == []  # (a folder of scores only)


@pytest.mark.parametrize("change, says", [
    ("{not json", "run.json: line 1, column 2: not JSON"),
    (b"{\"policy\": \"\xff\"}", "run.json: line 1, column 13: not UTF-8 text (byte 0xff)"),
    ("[1, 2]", "run.json: a JSON array, not an object"),
    pytest.param("[" * 100_000 + "]" * 100_000, "run.json: not JSON (nested too deeply)",
                 id="nested"),
    (_with(roundz=3), "run.json: unknown key \"roundz\"; did you mean 'rounds'?"),
    (_without("policy"), 'run.json: no "policy"'),
    (_with(rounds="3"), 'run.json: rounds is "3": input should be a valid integer'),
    (_with(rounds=1.5), "run.json: rounds is 1.5"),
    (_with(rounds=0), "run.json: rounds is 0, not at least 1"),
    (_with(scenes="scene1"), 'run.json: scenes is "scene1"'),
    (_with(scenes=["Scene 1"]), 'run.json: scenes[0] is "Scene 1", not a scene name'),
    (_with(levels=["L0", "L9"]), 'run.json: levels[1] is "L9", not one of L0, L1, L2, L3'),
    (_with(levels=[]), "run.json: levels is empty"),
    (_with(video="sometimes"), 'run.json: video is "sometimes", not one of none'),
    (_with(instruction_mode="loud"), 'run.json: instruction_mode is "loud"'),
    (_with(spec_digest="abc"), 'run.json: spec_digest is "abc", not a sha256 digest'),
    (_with(tasks=["pickup"]), 'run.json: tasks[0] is "pickup", not a task id'),
    (_with(sample=0), "run.json: sample is 0, not at least 1"),
    (_with(policy_timeout=-1), "run.json: policy_timeout is -1"),
    (_with(shard="5/4"), "run.json: shard '5/4': expected I/N"),
    (_with(provenance="mine"), "run.json: provenance is a JSON string, not an array"),
    (_with(provenance=[{"cpuu": "x"}]),
     "run.json: provenance[0]: unknown key \"cpuu\"; did you mean 'cpu'?"),
    (_with(provenance=[{"numpy": 2}]), "run.json: provenance[0].numpy is 2, not a string or"),
])
def test_a_bad_run_json_names_the_file_and_field(tmp_path, change, says):
    folder = _run_json(tmp_path, change) if not isinstance(change, bytes) else None
    if folder is None:
        folder = _copied_run(tmp_path)
        (folder / "run.json").write_bytes(change)
    _refused(lambda: load_options(folder), str(folder / "run.json"), says)


def test_report_stops_at_a_bad_run_json_with_one_line(tmp_path, capsys):
    folder = _run_json(tmp_path, _with(levels=["L0", "L7"]))
    assert "run.json: levels[1] is \"L7\"" in _cli_error(capsys, "report", str(folder))


# -- RUN/summary.json --------------------------------------------------------------------------

@pytest.mark.parametrize("summary, says", [
    ("{oops", "summary.json: line 1, column 2: not JSON"),
    ('{"episodes": "many"}', 'summary.json: episodes is "many", not a whole number from 0'),
    ('{"episodes": -3}', "summary.json: episodes is -3, not a whole number from 0"),
    ('{"episodes": 1.5}', "summary.json: episodes is 1.5"),
    ('{"cells": {}}', 'summary.json: no "episodes"'),
    ("[]", "summary.json: a JSON array, not an object"),
])
def test_a_bad_summary_names_the_file_and_field(tmp_path, summary, says):
    folder = _copied_run(tmp_path)
    assert summarised_episodes(folder) == 6350
    (folder / "summary.json").write_text(summary)
    _refused(lambda: summarised_episodes(folder), str(folder / "summary.json"), says)


# -- RUN/episodes.jsonl ----------------------------------------------------------------------

def _results(tmp_path: Path, *changes: dict) -> Path:
    records = [fake_record("pickup_left_cube", "L0", 1.0, 1.0, True, "instructed"),
               fake_record("pickup_right_cube", "L1", 0.5, 0.25, False, None)]
    records += [dict(records[0], **change) for change in changes]
    path = tmp_path / "episodes.jsonl"
    path.write_text("".join(json.dumps(r) + "\n" for r in records))
    return path


def test_the_records_of_episodes_jsonl_are_checked_in_range_and_shape(tmp_path):
    valid = _results(tmp_path)
    assert [r["episode"] for r in read_results(valid)] == ["scene2/L0/pickup_left_cube#r1",
                                                           "scene2/L1/pickup_right_cube#r1"]
    path = _results(tmp_path, {"episode": "scene2/L0/pickup_left_cube#r2", "intent_score": 500})
    _refused(lambda: read_results(path), f"{path} has 1 corrupt line: line 3: 'intent_score' "
             "is 500, not a number from 0 to 1", kind=CorruptResultsError)


@pytest.mark.parametrize("change, says", [
    ({"execution_score": float("nan")}, "'execution_score' is NaN, not a finite number"),
    ({"execution_score": -1}, "'execution_score' is -1, not a number from 0 to 1"),
    ({"episode": "scene2/L9/pickup_left_cube#r2", "level": "L9",
      "task": "scene2/L9/pickup_left_cube"}, "'episode' names the level \"L9\""),
    ({"episode": "anything"}, "'episode' is \"anything\", not an episode id"),
    ({"episode": "scene2/L0/pickup_left_cube#r2", "task": "scene2/L0/other"},
     "'task' is \"scene2/L0/other\", but the episode id"),
    ({"episode": "scene2/L0/pickup_left_cube#r2", "scene": "scene3"},
     ("'scene' is \"scene3\", but the episode id \"scene2/L0/pickup_left_cube#r2\" says "
      "\"scene2\"")),
    ({"episode": "scene2/L0/pickup_left_cube#r2", "level": "L1"}, "'level' is \"L1\""),
])
def test_a_bad_record_is_a_corrupt_line_naming_its_field(tmp_path, change, says):
    path = _results(tmp_path, change)
    _refused(lambda: read_results(path), f"{path} has 1 corrupt line: line 3: {says}",
             kind=CorruptResultsError)


# -- task lists --------------------------------------------------------------------------------

TASK = {"id": "a", "scene": "scene2", "level": "L2", "layout": "default",
        "instruction": "Use your left arm to pick up the blue cylinder and place it in the "
                       "rightmost bowl."}


def test_a_task_list_nested_too_deeply_or_too_large_is_named(tmp_path, monkeypatch):
    from robofollow.audit import task_list

    path = tmp_path / "tasks.jsonl"
    path.write_text(json.dumps(TASK) + "\n" + "[" * 100_000 + "\n")
    _refused(lambda: task_list.read_task_list(path), f"{path}:2: line: Invalid JSON")
    path.write_text(json.dumps(TASK) + "\n")
    assert task_list.read_task_list(path)[0].id == "a"
    monkeypatch.setattr(task_list, "MAX_TASK_LIST_BYTES", 100)
    _refused(lambda: task_list.read_task_list(path), str(path), "larger than")


@pytest.mark.parametrize("expect, says", [
    ({"steps": [{"waypoints": [[1, "a"], ["b", 2]]}]},
     "expect: steps.0.waypoints.0.0: Input should be 'via' or 'avoid'"),
    ({"steps": [{"waypoints": [[{"a": 1}], [1]]}]}, "expect: steps.0.waypoints.0.0"),
    ({"steps": [{"arm": 5}]}, "expect: steps.0.arm: Input should be 'left' or 'right'"),
    ({"steps": [{"yaw_degrees": "x"}]}, "expect: steps.0.yaw_degrees"),
    ({"branch": {"x": [1, "a"]}}, "expect: branch"),
])
def test_a_task_lists_expectation_of_the_wrong_type_is_an_invalid_finding(tmp_path, expect,
                                                                        says):
    from robofollow.audit.task_list import ListedTask, _expectation

    with pytest.raises(ValueError) as caught:
        _expectation(ListedTask(**TASK, expect=expect).expect)
    assert says in f"expect: {caught.value}"


def test_the_audit_cli_reports_a_badly_typed_expectation_as_a_finding(tmp_path, capsys):
    path = tmp_path / "tasks.jsonl"
    path.write_text(json.dumps(dict(TASK, expect={"steps": [{"waypoints": [[1, "a"],
                                                                            ["b", 2]]}]}))
                    + "\n")
    status, out, err = run_cli(capsys, "audit", "--tasks", str(path))
    assert status == 1 and "Traceback" not in err
    assert "a: expect: steps.0.waypoints.0.0: Input should be 'via' or 'avoid'" in out


# -- checkpoints -------------------------------------------------------------------------------

@pytest.fixture
def ckpt(tmp_path) -> Path:
    folder = tmp_path / "ckpt"
    shutil.copytree(BASELINES / "scene2-blind", folder)
    return folder


def _edit_policy(folder: Path, change) -> Path:
    meta = json.loads((folder / "policy.json").read_text())
    change(meta)
    (folder / "policy.json").write_text(json.dumps(meta))
    return folder / "policy.json"


def _edit_params(folder: Path, change) -> Path:
    with np.load(folder / "params.npz") as data:
        params = {key: data[key] for key in data.files}
    change(params)
    with open(folder / "params.npz", "wb") as f:
        np.savez(f, **params)
    return folder / "params.npz"


def test_a_shipped_checkpoint_loads_as_before_and_an_extra_key_is_refused(ckpt):
    from robofollow.learn import checkpoint

    loaded = checkpoint.load(ckpt)
    with np.load(BASELINES / "scene2-blind" / "params.npz") as data:
        assert set(data.files) == set(loaded.params)
        assert all(np.array_equal(data[k], loaded.params[k]) for k in data.files)
    assert loaded.arch.hidden == 512 and loaded.execute == 25
    path = _edit_policy(ckpt, lambda meta: meta.update(vocabulary=[]))
    _refused(lambda: checkpoint.load(ckpt), f"{path}: unknown key \"vocabulary\"; did you mean "
             "'vocab'?")


def _set(*keys, value):
    def change(meta):
        target = meta
        for key in keys[:-1]:
            target = target[key]
        target[keys[-1]] = value
    return change


def _drop(*keys):
    def change(meta):
        target = meta
        for key in keys[:-1]:
            target = target[key]
        del target[keys[-1]]
    return change


@pytest.mark.parametrize("change, says", [
    (_drop("vocab"), 'no "vocab"'),
    (_set("architecture", "hidden", value="512"),
     'architecture.hidden is "512": input should be a valid integer'),
    (_set("architecture", "hidden", value=-3), "architecture.hidden holds -3, not a whole"),
    (_set("architecture", "hiden", value=512),
     "architecture: unknown key \"hiden\"; did you mean 'hidden'?"),
    (_set("architecture", "kind", value="psychic"), 'architecture.kind is "psychic"'),
    (_set("architecture", "kernels", value=[5, 3]), "architecture.kernels has 2 layers, but channels has 3"),
    (_set("architecture", "vocab_size", value=10 ** 9), "architecture describes a network of"),
    (_set("vocab", value=["<pad>"]), "vocab holds 1 words, but architecture.vocab_size is 2"),
    (_set("vocab", value="words"), 'vocab is "words", not a list of words'),
    (_set("normalization", "state_std", value=[0.0] * 14),
     "normalization.state_std[0] is 0, not above 0"),
    (_set("normalization", "action_mean", value=[1.0] * 3),
     "normalization.action_mean is [1.0, 1.0, 1.0], not a list of 14 numbers"),
    (_set("normalization", "objects_mean", value=[0.0] * 14),
     "normalization: unknown key \"objects_mean\""),
    (_set("execute", value=0), "execute is 0, not a whole number from 1 to the chunk (50)"),
    (_set("execute", value="25"), 'execute is "25"'),
    (_set("training", value=[]), "training is [], not an object"),
])
def test_a_bad_policy_json_names_the_file_and_field(ckpt, change, says):
    from robofollow.learn import checkpoint

    path = _edit_policy(ckpt, change)
    _refused(lambda: checkpoint.load(ckpt), f"{path}: {says}", kind=checkpoint.CheckpointError)


def test_a_policy_json_that_is_not_json_names_its_line(ckpt):
    from robofollow.learn import checkpoint

    (ckpt / "policy.json").write_text('{\n  "format": oops\n}')
    _refused(lambda: checkpoint.load(ckpt), f"{ckpt / 'policy.json'}: line 2, column 13: not "
             "JSON")


@pytest.mark.parametrize("change, says", [
    (lambda p: p.update({"trunk1.w": p["trunk1.w"][:, :7]}),
     "trunk1.w has the shape (512, 7), but the architecture needs (512, 512)"),
    (lambda p: p.pop("head.b"), 'lacks the array "head.b", which the architecture has'),
    (lambda p: p.update(extra=np.zeros(3, np.float32)),
     'holds the array "extra", which the architecture has not'),
    (lambda p: p["head.b"].__setitem__(0, np.nan), "head.b holds values that are not finite"),
    (lambda p: p.update({"head.b": p["head.b"].astype(np.int32)}), "head.b holds int32"),
])
def test_bad_params_name_the_array(ckpt, change, says):
    from robofollow.learn import checkpoint

    path = _edit_params(ckpt, change)
    _refused(lambda: checkpoint.load(ckpt), f"{path}: {says}", kind=checkpoint.CheckpointError)


def test_a_truncated_params_file_is_not_a_readable_checkpoint(ckpt):
    from robofollow.learn import checkpoint

    path = ckpt / "params.npz"
    path.write_bytes(path.read_bytes()[:100_000])
    _refused(lambda: checkpoint.load(ckpt), f"{path}: not a readable baseline checkpoint",
             kind=checkpoint.CheckpointError)
    (ckpt / "optimizer.npz").write_bytes(path.read_bytes())
    _refused(lambda: checkpoint.load_optimizer(ckpt), "optimizer.npz: cannot resume",
             kind=checkpoint.CheckpointError)
