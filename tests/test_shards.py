"""`eval --shard I/N` and `merge`: a run made in two shards and merged equals the run made in
one piece (episode records identical apart from timings; the same options, summary and score
file); a merge with a missing or doubled episode or shard is refused, naming it, and writes
nothing."""

from __future__ import annotations

import json

import pytest

from robofollow.cli import main

pytestmark = pytest.mark.slow

RUN = ["--policy", "expert", "--scenes", "scene1", "--levels", "L0,L1", "--sample", "3",
       "--rounds", "2", "--workers", "1", "--quiet"]


def _records(run) -> dict[str, dict]:
    records = {}
    for line in (run / "episodes.jsonl").read_text().splitlines():
        record = json.loads(line)
        record.pop("seconds")  # the timing
        records[record["episode"]] = record
    return records


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("shards")
    for index in (1, 2):
        assert main(["eval", *RUN, "--shard", f"{index}/2", "--out", str(root / f"s{index}")]) == 0
    assert main(["eval", *RUN, "--out", str(root / "whole")]) == 0
    return root


def test_two_shards_merged_equal_the_run_in_one_piece(runs):
    first, second = _records(runs / "s1"), _records(runs / "s2")
    assert first and second and not set(first) & set(second)
    assert main(["merge", str(runs / "s1"), str(runs / "s2"), "--out", str(runs / "merged")]) == 0
    merged, whole = runs / "merged", runs / "whole"
    assert _records(merged) == _records(whole) and len(_records(whole)) == 12
    for name in ("run.json", "summary.json"):
        assert json.loads((merged / name).read_text()) == json.loads((whole / name).read_text())
    assert (merged / "scores.csv.gz").read_bytes() == (whole / "scores.csv.gz").read_bytes()
    assert (merged / "report.md").is_file()


def test_a_merge_that_misses_or_doubles_is_refused_naming_it(runs, tmp_path, capsys):
    lines = (runs / "s2" / "episodes.jsonl").read_text().splitlines(keepends=True)
    dropped = json.loads(lines[0])["episode"]
    short = tmp_path / "short"
    short.mkdir()
    (short / "run.json").write_text((runs / "s2" / "run.json").read_text())
    (short / "episodes.jsonl").write_text("".join(lines[1:]))
    cases = [([runs / "s1", short], (f"1 episode(s) missing (an unfinished shard? finish it "
                                     f"with eval --resume): {dropped}")),
             ([runs / "s1", runs / "s1"], "missing 2/2; doubled 1/2"),
             ([runs / "s1"], "missing 2/2"),
             ([runs / "whole", runs / "s1"], "is a whole run, not a shard")]
    doubled = tmp_path / "doubled"
    doubled.mkdir()
    (doubled / "run.json").write_text((runs / "s1" / "run.json").read_text())
    (doubled / "episodes.jsonl").write_text((runs / "s1" / "episodes.jsonl").read_text()
                                           + lines[0])  # one of shard 2's episodes too
    cases.append(([doubled, runs / "s2"], f"1 episode(s) in more than one shard: {dropped}"))
    for index, (shards, message) in enumerate(cases):
        out = tmp_path / f"out{index}"
        assert main(["merge", *map(str, shards), "--out", str(out)]) == 1
        err = capsys.readouterr().err
        assert message in err and "Traceback" not in err, err
        assert not out.exists()


def test_a_shard_is_checked_before_anything_runs(tmp_path, capsys):
    assert main(["eval", *RUN, "--shard", "3/2", "--out", str(tmp_path / "run")]) == 2
    assert "shard '3/2': expected I/N with 1 <= I <= N" in capsys.readouterr().err
    assert not (tmp_path / "run").exists()
