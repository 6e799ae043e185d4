"""`eval --until-separated RUN_B`: rounds are added one at a time and the run stops at the
first look where the declared test (average Intent, paired sign-flip over tasks, at
0.05 / --rounds) separates it from RUN_B; a run that does not differ runs every round."""

from __future__ import annotations

import json

import pytest

from robofollow.cli import main

pytestmark = pytest.mark.slow

RUN = ["--scenes", "scene1", "--levels", "L0,L1", "--sample", "4", "--workers", "1",
       "--quiet"]


@pytest.fixture(scope="module")
def noop(tmp_path_factory):
    run = tmp_path_factory.mktemp("sequential") / "noop"
    assert main(["eval", "--policy", "noop", *RUN, "--rounds", "3", "--out", str(run)]) == 0
    return run


def _rounds(run) -> set[int]:
    return {json.loads(line)["round"] for line in (run / "episodes.jsonl").read_text().splitlines()}


def test_a_run_that_differs_stops_after_the_first_round(noop, tmp_path, capsys):
    run = tmp_path / "expert"
    assert main(["eval", "--policy", "expert", *RUN, "--rounds", "3", "--until-separated",
                 str(noop), "--out", str(run)]) == 0
    stopped = json.loads((run / "sequential.json").read_text())
    assert stopped["separated"] and stopped["stopped_after_round"] == 1
    assert stopped["threshold"] == pytest.approx(0.05 / 3) and stopped["p"] < 0.05 / 3
    assert stopped["difference"] == pytest.approx(100.0)
    assert _rounds(run) == {1}
    assert "after round 1: average Intent +100.0 against noop" in capsys.readouterr().err


def test_a_run_that_does_not_differ_runs_every_round(noop, tmp_path):
    run = tmp_path / "noop-again"
    assert main(["eval", "--policy", "noop", *RUN, "--rounds", "3", "--until-separated",
                 str(noop), "--out", str(run)]) == 0
    stopped = json.loads((run / "sequential.json").read_text())
    assert not stopped["separated"] and stopped["stopped_after_round"] == 3
    assert stopped["p"] == 1 and _rounds(run) == {1, 2, 3}


def test_the_other_run_and_a_shard_are_checked_first(tmp_path, capsys):
    assert main(["eval", "--policy", "expert", *RUN, "--until-separated",
                 str(tmp_path / "nowhere"), "--out", str(tmp_path / "run")]) == 1
    assert "no such run folder" in capsys.readouterr().err
    assert main(["eval", "--policy", "expert", *RUN, "--until-separated", str(tmp_path),
                 "--shard", "1/2", "--out", str(tmp_path / "run")]) == 2
    assert "a shard is a part of one" in capsys.readouterr().err
    assert not (tmp_path / "run").exists()


def test_rounds_past_the_benchmarks_own_stop_at_its_last_round(noop, tmp_path, capsys):
    """--rounds beyond the rounds the benchmark holds looks once per round it holds (10),
    then stops, said on stderr: no pass with nothing to run."""
    run = tmp_path / "many"
    assert main(["eval", "--policy", "noop", "--scenes", "scene1", "--levels", "L0",
                 "--sample", "1", "--workers", "1", "--quiet", "--rounds", "1000000",
                 "--until-separated", str(noop), "--out", str(run)]) == 0
    stopped = json.loads((run / "sequential.json").read_text())
    assert stopped["looks"] == 10 and stopped["stopped_after_round"] == 10
    assert stopped["threshold"] == pytest.approx(0.05 / 10) and _rounds(run) == set(range(1, 11))
    err = capsys.readouterr().err
    assert "--rounds 1000000: the benchmark holds 10 rounds of these tasks, so at most 10 looks" \
        in err and "after round 11" not in err
