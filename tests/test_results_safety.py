"""Nothing lost, nothing corrupted: a finished run is never resumed into or written over, no
write follows a link out of a run folder or --out, resume and merge compare every option both
ways (shards and control arms included), two results never land on one path, and shard
counts are bounded by the episodes."""

from __future__ import annotations

import json
import os
import shutil
import signal
from contextlib import contextmanager
from pathlib import Path

import pytest

from robofollow.cli import main

pytestmark = pytest.mark.slow

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results"
RUN = ["--policy", "noop", "--scenes", "scene2", "--levels", "L0", "--sample", "2",
       "--rounds", "1", "--workers", "1", "--quiet"]


def _files(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file() and p.name != ".lock"}


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    """A small finished run with its full records."""
    out = tmp_path_factory.mktemp("finished") / "run"
    assert main(["eval", *RUN, "--out", str(out)]) == 0
    return out


def test_a_shipped_run_is_never_resumed(tmp_path, capsys):
    run = tmp_path / "noop"
    shutil.copytree(RESULTS / "noop", run)
    before = _files(run)
    assert main(["eval", "--policy", "noop", "--out", str(run), "--resume", "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "holds a finished run that keeps only its scores" in err and "Traceback" not in err
    assert _files(run) == before


def test_a_finished_run_resumed_is_read_not_written(finished, tmp_path, capsys):
    run = tmp_path / "run"
    shutil.copytree(finished, run)
    kept = {name: _files(run)[name] for name in ("episodes.jsonl", "summary.json",
                                                 "scores.csv.gz", "run.json")}
    assert main(["eval", *RUN, "--out", str(run), "--resume"]) == 0
    assert "every episode is already recorded; nothing to run" in capsys.readouterr().err
    assert {name: _files(run)[name] for name in kept} == kept


def test_a_shipped_run_with_an_emptied_results_file_is_not_run_again(tmp_path, capsys):
    """`touch RUN/episodes.jsonl` beside a shipped run's scores does not make --resume run
    its 6,350 episodes again over them: refused before anything runs."""
    run = tmp_path / "noop"
    shutil.copytree(RESULTS / "noop", run)
    (run / "episodes.jsonl").touch()
    before = _files(run)
    assert main(["eval", "--policy", "noop", "--out", str(run), "--resume", "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "keeps 0 of the 6350 episodes its summary counts; it is not resumed" in err
    assert _files(run) == before


def test_a_resume_that_runs_nothing_adds_no_environment(finished, tmp_path, capsys):
    """A finished run resumed in another environment (another NumPy, say) runs nothing, so
    its provenance stays as it was."""
    run = tmp_path / "run"
    shutil.copytree(finished, run)
    options = json.loads((run / "run.json").read_text())
    options["provenance"][0]["numpy"] = "2.3.5"
    (run / "run.json").write_text(json.dumps(options))
    before = (run / "run.json").read_bytes()
    assert main(["eval", *RUN, "--out", str(run), "--resume"]) == 0
    err = capsys.readouterr().err
    assert "nothing to run" in err and "another environment" not in err
    assert (run / "run.json").read_bytes() == before


@pytest.mark.parametrize("linked", ["report.html", "tasks.html", "table1.csv", "figures"])
def test_no_write_follows_a_link_out_of_the_run(finished, tmp_path, capsys, linked):
    run = tmp_path / "run"
    shutil.copytree(finished, run)
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "keep.txt").write_text("mine")
    target = outside if linked == "figures" else outside / "keep.txt"
    shutil.rmtree(run / linked) if (run / linked).is_dir() else (run / linked).unlink(
        missing_ok=True)
    (run / linked).symlink_to(target)
    assert main(["report", str(run), "--export", "csv"]) == 1
    err = capsys.readouterr().err
    assert "is a symbolic link" in err and "Traceback" not in err, err
    assert _files(outside) == {"keep.txt": b"mine"}


def test_resume_does_not_append_through_a_linked_episode_file(finished, tmp_path, capsys):
    run = tmp_path / "run"
    shutil.copytree(finished, run)
    (run / "summary.json").unlink()  # (an unfinished run)
    outside = tmp_path / "elsewhere.jsonl"
    outside.write_bytes((run / "episodes.jsonl").read_bytes().split(b"\n", 1)[0] + b"\n")
    (run / "episodes.jsonl").unlink()
    (run / "episodes.jsonl").symlink_to(outside)
    before = outside.read_bytes()
    assert main(["eval", *RUN, "--out", str(run), "--resume"]) == 1
    assert "is a symbolic link" in capsys.readouterr().err
    assert outside.read_bytes() == before


@pytest.mark.parametrize(("option", "value", "recorded"), [
    ("--shard", "1/2", "1/2"),  # a shard resumed without its shard
    ("--controls", "empty", ["empty"]),  # a run resumed with other control arms
])
def test_a_run_resumed_without_an_option_it_was_run_with_is_refused(tmp_path, capsys, option,
                                                                       value, recorded):
    run = tmp_path / "run"
    assert main(["eval", *RUN, option, value, "--out", str(run)]) == 0
    (run / "summary.json").unlink()  # (as if interrupted)
    capsys.readouterr()
    assert main(["eval", *RUN, "--out", str(run), "--resume"]) == 1
    key = option.removeprefix("--")
    err = capsys.readouterr().err
    assert f"was run with other options ({key} differ)" in err, err
    assert json.loads((run / "run.json").read_text())[key] == recorded


def test_merge_joins_the_shards_control_arms(tmp_path, capsys):
    shards = [tmp_path / f"s{i}" for i in (1, 2)]
    for index, shard in enumerate(shards, start=1):
        assert main(["eval", *RUN, "--shard", f"{index}/2", "--controls", "empty",
                     "--out", str(shard)]) == 0
    assert main(["merge", *map(str, shards), "--out", str(tmp_path / "merged")]) == 0
    arm = tmp_path / "merged" / "controls" / "empty"
    assert json.loads((arm / "summary.json").read_text())["episodes"] == 2
    assert json.loads((arm / "run.json").read_text())["instruction_mode"] == "empty"
    assert json.loads((tmp_path / "merged" / "run.json").read_text())["controls"] == ["empty"]
    assert "Language effect: instructed − empty" in (tmp_path / "merged" / "report.md").read_text()
    shutil.rmtree(shards[1] / "controls")
    capsys.readouterr()
    assert main(["merge", *map(str, shards), "--out", str(tmp_path / "again")]) == 1
    assert "holds the control arms none but was run with empty" in capsys.readouterr().err
    assert not (tmp_path / "again").exists()


def test_two_comparisons_never_share_a_folder(tmp_path, capsys):
    a = RESULTS / "expert"
    others = [tmp_path / "x" / "run", tmp_path / "y" / "run"]
    for other, source in zip(others, ("noop", "blind"), strict=True):
        shutil.copytree(RESULTS / source, other)
    out = tmp_path / "d"
    assert main(["compare", str(a), *map(str, others), "--out", str(out)]) == 0
    capsys.readouterr()
    written = sorted(p.name for p in out.iterdir())
    assert written == ["expert-vs-x-run", "expert-vs-y-run"]
    for other in others:
        result = json.loads((out / f"expert-vs-{other.parent.name}-run" / "compare.json")
                            .read_text())
        assert result["b"] == str(other)


def test_runs_whose_paths_read_alike_when_joined_get_folders_of_their_own(tmp_path, capsys):
    """p/a/b-c and p/a-b/c join to one name: the later gets -2, and no comparison is lost."""
    a = RESULTS / "expert"
    others = [tmp_path / "p" / "a" / "b-c", tmp_path / "p" / "a-b" / "c",
              tmp_path / "q" / "a" / "b-c"]
    for other in others:
        shutil.copytree(RESULTS / "noop", other)
    out = tmp_path / "d"
    assert main(["compare", str(a), *map(str, others), "--out", str(out)]) == 0
    capsys.readouterr()
    written = sorted(p.name for p in out.iterdir())
    assert written == ["expert-vs-p-a-b-c", "expert-vs-p-a-b-c-2", "expert-vs-q-a-b-c"]
    assert sorted(json.loads((out / name / "compare.json").read_text())["b"]
                  for name in written) == sorted(map(str, others))


@pytest.mark.parametrize("shard", ["1/99999999999999999999", "1/100", "1/²"])
def test_a_shard_count_is_bounded_by_the_episodes(tmp_path, capsys, shard):
    assert main(["eval", *RUN, "--shard", shard, "--out", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err
    errors = [line for line in err.splitlines() if not line.startswith("specs: ")]
    assert len(errors) == 1 and "shard" in errors[0] and "Traceback" not in err, err
    assert not (tmp_path / "run").exists()


def test_merge_bounds_a_recorded_shard_count(finished, tmp_path, capsys):
    shard = tmp_path / "s1"
    shutil.copytree(finished, shard)
    options = json.loads((shard / "run.json").read_text())
    (shard / "run.json").write_text(json.dumps(dict(options, shard="1/999999999")))
    assert main(["merge", str(shard), "--out", str(tmp_path / "merged")]) in (1, 2)
    err = capsys.readouterr().err
    assert "at most 2 shards" in err and "Traceback" not in err, err


def test_a_merge_records_and_names_every_environment_its_shards_ran_in(tmp_path, capsys):
    shards = [tmp_path / f"s{i}" for i in (1, 2)]
    for index, shard in enumerate(shards, start=1):
        assert main(["eval", *RUN, "--shard", f"{index}/2", "--out", str(shard)]) == 0
    options = json.loads((shards[1] / "run.json").read_text())
    options["provenance"][0]["mujoco"] = "4.0.1"
    (shards[1] / "run.json").write_text(json.dumps(options))
    capsys.readouterr()
    assert main(["merge", *map(str, shards), "--out", str(tmp_path / "merged")]) == 0
    assert "the shards ran in different environments (mujoco" in capsys.readouterr().err
    made = json.loads((tmp_path / "merged" / "run.json").read_text())["provenance"]
    assert [entry["mujoco"] for entry in made] == [made[0]["mujoco"], "4.0.1"]


def test_a_report_says_which_declared_control_arm_is_missing(tmp_path, capsys):
    """A run whose run.json declares a control arm its folder lacks (a copy without it, a
    merge cut short) is reported with a warning naming the arm, never silently without it."""
    run = tmp_path / "run"
    assert main(["eval", *RUN, "--controls", "empty", "--out", str(run)]) == 0
    shutil.rmtree(run / "controls" / "empty")
    capsys.readouterr()
    assert main(["report", str(run)]) == 0
    err = capsys.readouterr().err
    assert "declares the control arm(s) empty, which" in err and "lacks" in err


@pytest.mark.parametrize("linked", ["controls", "controls/empty"])
def test_a_control_arm_behind_a_link_is_neither_written_nor_read(tmp_path, capsys, linked):
    """RUN/controls or RUN/controls/empty a link elsewhere: a resume refuses before writing
    (it wrote a whole arm outside the run), and report refuses to read it."""
    run = tmp_path / "run"
    assert main(["eval", *RUN, "--controls", "empty", "--shard", "1/2", "--out", str(run)]) == 0
    outside = tmp_path / "outside"
    shutil.move(str(run / linked), str(outside))
    (run / linked).symlink_to(outside, target_is_directory=True)
    before = _files(outside)
    capsys.readouterr()
    assert main(["eval", *RUN, "--controls", "empty", "--shard", "1/2", "--out", str(run),
                 "--resume"]) == 1
    assert "is a symbolic link" in capsys.readouterr().err
    assert main(["report", str(run)]) == 1
    assert "is a symbolic link" in capsys.readouterr().err
    assert _files(outside) == before


# -- every file a run keeps is read through a check (issue: hardening, second round) ----------

def _paths(value, path=()):
    """Every field path of a JSON value (object keys and list indices), outermost first."""
    if isinstance(value, dict):
        for key, item in value.items():
            yield (*path, key)
            yield from _paths(item, (*path, key))
    elif isinstance(value, list):
        for index, item in enumerate(value):
            yield (*path, index)
            yield from _paths(item, (*path, index))


def _wrong(value):
    """A value of another JSON type than `value`'s (text for a number, a list for text, ...)."""
    if isinstance(value, bool):
        return "yes"
    if isinstance(value, int | float):
        return "1"
    if isinstance(value, str):
        return [value]
    return 7 if value is not None else {"x": 1}


def _with_wrong(record: dict, path: tuple) -> dict:
    changed = json.loads(json.dumps(record))
    inner = changed
    for key in path[:-1]:
        inner = inner[key]
    inner[path[-1]] = _wrong(inner[path[-1]])
    return changed


def test_every_field_of_an_episode_record_at_a_wrong_type_is_a_corrupt_line(finished):
    from robofollow.eval.running.episode_record import record_problem

    record = json.loads((finished / "episodes.jsonl").read_text().splitlines()[0])
    assert record_problem(record) is None
    paths = list(_paths(record))
    assert len(paths) > 50
    for path in paths:
        problem = record_problem(_with_wrong(record, path))
        assert problem and repr(path[0]) in problem, (path, problem)


def _damaged(finished: Path, folder: Path, field: str) -> Path:
    """A copy of the finished run whose first record holds `field` at a wrong type, and whose
    summary is gone (an unfinished run: resume reads its records)."""
    shutil.copytree(finished, folder)
    lines = (folder / "episodes.jsonl").read_text().splitlines(keepends=True)
    lines[0] = json.dumps(_with_wrong(json.loads(lines[0]), (field,))) + "\n"
    (folder / "episodes.jsonl").write_text("".join(lines))
    return folder


def _one_line_error(capsys, *parts: str) -> str:
    """The one error line a command printed (beside lines that say what it reads)."""
    err = capsys.readouterr().err
    errors = [line for line in err.splitlines() if line.startswith("error")]
    assert "Traceback" not in err and len(errors) == 1, err
    for part in parts:
        assert part in errors[0], (part, err)
    return errors[0]


@pytest.mark.parametrize("field", ["hashes", "chance", "stages", "followed_intent",
                                   "executed_behaviour", "observed", "clipped", "error",
                                   "instruction"])
def test_a_record_with_a_field_of_the_wrong_type_is_refused_by_report(finished, tmp_path,
                                                                        capsys, field):
    run = _damaged(finished, tmp_path / "run", field)
    capsys.readouterr()
    assert main(["report", str(run)]) == 1
    _one_line_error(capsys, "1 corrupt line: line 1:", repr(field))


def test_a_record_of_the_wrong_type_is_refused_by_every_command_that_reads_it(finished,
                                                                              tmp_path, capsys):
    run = _damaged(finished, tmp_path / "run", "hashes")
    shard = tmp_path / "shard"
    assert main(["eval", *RUN, "--shard", "1/1", "--out", str(shard)]) == 0
    _damaged(shard, tmp_path / "bad-shard", "hashes")
    capsys.readouterr()
    commands = [["report", str(run)], ["compare", str(run), str(finished)],
                ["eval", *RUN, "--out", str(run), "--resume"],
                ["reproduce", str(run), "--episodes", "1"],
                ["merge", str(tmp_path / "bad-shard"), "--out", str(tmp_path / "merged")]]
    for argv in commands:
        assert main(argv) == 1, argv
        _one_line_error(capsys, "corrupt line", "'hashes'")
    assert not (tmp_path / "merged").exists()


def test_a_hard_linked_results_file_is_not_appended_to(finished, tmp_path, capsys):
    run = tmp_path / "run"
    shutil.copytree(finished, run)
    (run / "summary.json").unlink()
    lines = (run / "episodes.jsonl").read_bytes().split(b"\n")
    (run / "episodes.jsonl").write_bytes(lines[0] + b"\n")
    elsewhere = tmp_path / "elsewhere.jsonl"
    os.link(run / "episodes.jsonl", elsewhere)
    before = elsewhere.read_bytes()
    capsys.readouterr()
    assert main(["eval", *RUN, "--out", str(run), "--resume"]) == 1
    _one_line_error(capsys, "hard-linked elsewhere (2 names)")
    assert elsewhere.read_bytes() == before


def test_an_out_folder_whose_name_is_not_utf8_is_refused_before_anything_runs(tmp_path,
                                                                               capsys):
    out = os.fsdecode(bytes(tmp_path) + b"/run\xff")
    assert main(["eval", *RUN, "--out", out]) == 2
    _one_line_error(capsys, "run\\xff (the out argument) is not UTF-8 text (byte 0xff)")
    assert list(tmp_path.iterdir()) == []


@contextmanager
def _no_hang(seconds: int = 60):
    def stop(*_):
        raise TimeoutError(f"hung for {seconds} s")
    previous = signal.signal(signal.SIGALRM, stop)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


@pytest.mark.parametrize("name", ["episodes.jsonl", "run.json"])
@pytest.mark.parametrize("kind", ["oversized", "fifo", "/dev/zero"])
def test_a_run_file_that_is_huge_a_fifo_or_a_device_is_refused_on_resume_and_report(
        finished, tmp_path, capsys, name, kind):
    run = tmp_path / "run"
    shutil.copytree(finished, run)
    (run / "summary.json").unlink()
    path = run / name
    path.unlink()
    if kind == "oversized":
        with open(path, "wb") as f:
            f.truncate(300 * 1024 * 1024)  # (sparse: past the caps, on no disk)
    elif kind == "fifo":
        os.mkfifo(path)
    else:
        path.symlink_to("/dev/zero")
    says = {"oversized": "larger than", "fifo": "not a regular file",
            "/dev/zero": "not a regular file"}[kind]
    capsys.readouterr()
    with _no_hang():
        for argv in (["eval", *RUN, "--out", str(run), "--resume"], ["report", str(run)]):
            assert main(argv) in (1, 2), argv
            _one_line_error(capsys, str(path), says)


def test_a_report_of_an_unfinished_run_says_so_in_its_pages_and_on_stderr(finished, tmp_path,
                                                                           capsys):
    run = tmp_path / "run"
    shutil.copytree(finished, run)
    (run / "summary.json").unlink()  # (a run stopped before its end, or a merge cut short)
    capsys.readouterr()
    assert main(["report", str(run)]) == 0
    says = "An unfinished run (no summary.json): this report covers the 2 episodes recorded"
    assert says in capsys.readouterr().err
    assert says in (run / "report.md").read_text() and says in (run / "report.html").read_text()
    assert "unfinished" not in (finished / "report.md").read_text()


def test_a_merge_into_a_folder_an_eval_was_killed_in_before_its_first_write_finishes(
        tmp_path, capsys):
    """A folder holding only a lock and a write a kill cut short counts as new: the merge
    moves its run there (it stuck there for good: the folder could not be removed)."""
    shards = [tmp_path / f"s{i}" for i in (1, 2)]
    for index, shard in enumerate(shards, start=1):
        assert main(["eval", *RUN, "--shard", f"{index}/2", "--out", str(shard)]) == 0
    out = tmp_path / "merged"
    out.mkdir()
    (out / ".lock").write_text("12345\n")
    (out / "run.json.partial").write_text('{"policy": "no')
    assert main(["merge", *map(str, shards), "--out", str(out)]) == 0
    assert json.loads((out / "summary.json").read_text())["episodes"] == 2
    assert not (out / "run.json.partial").exists()
    assert not list(tmp_path.glob(".*.merging"))
