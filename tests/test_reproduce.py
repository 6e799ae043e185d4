"""Provenance and `robofollow reproduce`: a run records the environment that made it (run.json
and the report show it), and re-running its recorded episodes says what agrees: scores
always, trajectory hashes where the recorded environment matches, the differing versions
named where it does not."""

from __future__ import annotations

import gzip
import json
import shutil

import pytest

from robofollow.cli import main
from robofollow.eval.running.reproduce import sampled
from robofollow.provenance import FIELDS, environment

pytestmark = pytest.mark.slow

RUN = ["--policy", "expert", "--scenes", "scene2", "--levels", "L0,L1", "--sample", "2",
       "--rounds", "1", "--workers", "1", "--quiet"]


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    out = tmp_path_factory.mktemp("made") / "run"
    assert main(["eval", *RUN, "--out", str(out)]) == 0
    return out


def _copy(made, tmp_path):
    run = tmp_path / "run"
    shutil.copytree(made, run)
    return run


def _rewrite_records(run, change) -> None:
    lines = (run / "episodes.jsonl").read_text().splitlines()
    records = [json.loads(line) for line in lines]
    change(records[0])
    (run / "episodes.jsonl").write_text("".join(json.dumps(r) + "\n" for r in records))


def test_a_run_records_the_environment_that_made_it(made):
    recorded = json.loads((made / "run.json").read_text())["provenance"]
    assert recorded == [environment(False)] and set(recorded[0]) == set(FIELDS)
    assert recorded[0]["numpy"] and recorded[0]["mujoco"] and recorded[0]["cpu"]
    report = (made / "report.md").read_text()
    assert "## Provenance" in report
    assert f"NumPy {recorded[0]['numpy']}, MuJoCo {recorded[0]['mujoco']}" in report
    assert f"MuJoCo {recorded[0]['mujoco']}" in (made / "report.html").read_text()


def test_a_run_reproduces_bit_for_bit_in_its_own_environment(made, capsys):
    assert main(["reproduce", str(made), "--episodes", "3"]) == 0
    out = capsys.readouterr().out
    assert "scores (Intent, Execution, completion): 3 of 3 agree" in out
    assert "trajectory hashes: 3 of 3 agree (the recorded environment matches" in out


def test_a_score_that_differs_is_not_reproduced(made, tmp_path, capsys):
    run = _copy(made, tmp_path)
    _rewrite_records(run, lambda r: r.update(intent_score=r["intent_score"] / 2))
    episode = json.loads((run / "episodes.jsonl").read_text().splitlines()[0])["episode"]
    assert main(["reproduce", str(run), "--episode", episode]) == 1
    out = capsys.readouterr().out
    assert f"{episode}: IS 0.5000 / 1.0000" in out and "NOT reproduced" in out


def test_a_hash_that_differs_fails_only_where_the_environment_matches(made, tmp_path, capsys):
    run = _copy(made, tmp_path)
    _rewrite_records(run, lambda r: r["hashes"].update(trajectory="0" * 16))
    episode = json.loads((run / "episodes.jsonl").read_text().splitlines()[0])["episode"]
    assert main(["reproduce", str(run), "--episode", episode]) == 1
    assert f"{episode}: another trajectory" in capsys.readouterr().out
    options = json.loads((run / "run.json").read_text())
    options["provenance"][0]["mujoco"] = "3.17.0"
    (run / "run.json").write_text(json.dumps(options))
    assert main(["reproduce", str(run), "--episode", episode]) == 0
    out = capsys.readouterr().out
    assert (f"0 of 1 agree (the environment differs, so they need not agree: mujoco 3.17.0 / "
            f"{environment()['mujoco']} (recorded / here))") in out


@pytest.mark.parametrize("change,message", [
    (lambda r: r["hashes"].update(episode="0" * 16),
     "has hash 0000000000000000 in the run but {hash} in release v1: another episode under its "
     "id"),
    (lambda r: r.update(episode=r["episode"].replace("#r1", "#r11")),
     "is not in release v1, the run's benchmark"),
])
def test_an_episode_its_release_does_not_hold_is_named(made, tmp_path, capsys, change, message):
    """A recorded episode that is not its release's (another hash under its id, or an id the
    release lacks) stops reproduce before anything runs, in one line naming it."""
    run = _copy(made, tmp_path)
    first = json.loads((run / "episodes.jsonl").read_text().splitlines()[0])
    _rewrite_records(run, change)
    changed = json.loads((run / "episodes.jsonl").read_text().splitlines()[0])
    assert main(["reproduce", str(run), "--episode", changed["episode"]]) == 1
    err = capsys.readouterr().err.splitlines()
    assert err[-1] == (f"error: {run}: episode {changed['episode']} "
                       + message.format(hash=first["hashes"]["episode"])), err


def test_a_run_with_no_episode_is_not_called_reproduced(made, tmp_path, capsys):
    run = _copy(made, tmp_path)
    (run / "episodes.jsonl").write_text("")
    (run / "scores.csv.gz").unlink()
    assert main(["reproduce", str(run)]) == 1
    assert "records no episode: there is nothing to reproduce" in capsys.readouterr().err


def test_a_saved_run_reproduces_from_its_score_file(made, tmp_path, capsys):
    run = _copy(made, tmp_path)
    (run / "episodes.jsonl").unlink()
    assert main(["reproduce", str(run), "--episodes", "2"]) == 0
    assert "2 of 2 agree (the recorded environment matches" in capsys.readouterr().out
    with gzip.open(run / "scores.csv.gz", "rt") as text:
        assert "trajectory" in text.readline()


def test_the_sample_spreads_over_the_cells():
    records = [{"episode": f"s/{level}/t{i}#r1", "scene": "s", "level": level}
               for level in ("L0", "L1") for i in range(5)]
    chosen = sampled(records, 4)
    assert [r["episode"] for r in chosen] == ["s/L0/t1#r1", "s/L0/t3#r1", "s/L1/t1#r1",
                                              "s/L1/t3#r1"]
    assert len(sampled(records, 50)) == 10


def test_a_recorded_policy_that_is_gone_asks_for_another(made, tmp_path, capsys):
    run = _copy(made, tmp_path)
    options = json.loads((run / "run.json").read_text())
    (run / "run.json").write_text(json.dumps(dict(options, policy="runs/gone/ckpt-mine")))
    assert main(["reproduce", str(run)]) == 2
    err = capsys.readouterr().err
    assert "--policy re-runs its episodes with another" in err and "Traceback" not in err


def test_a_gone_checkpoint_folder_is_stood_in_for_by_the_shipped_one_and_judged(made, tmp_path,
                                                                                capsys):
    """A checkpoint folder named as a shipped baseline's (ckpt-NAME) that is not here is
    re-run as baseline:NAME, said on stderr; the scores decide: this run was the expert's, so
    the stand-in does not reproduce it."""
    run = _copy(made, tmp_path)
    options = json.loads((run / "run.json").read_text())
    (run / "run.json").write_text(json.dumps(dict(options, policy="runs/gone/ckpt-blind")))
    assert main(["reproduce", str(run), "--episodes", "2"]) == 1
    captured = capsys.readouterr()
    assert "the shipped baseline:blind stands in for it" in captured.err
    assert "NOT reproduced" in captured.out


def test_compare_names_what_differs_between_the_runs_environments(made, tmp_path, capsys):
    run = _copy(made, tmp_path)
    options = json.loads((run / "run.json").read_text())
    options["provenance"][0].update(numpy="2.3.5", cpu="another CPU")
    (run / "run.json").write_text(json.dumps(options))
    assert main(["compare", str(made), str(run)]) == 0
    err = capsys.readouterr().err
    assert (f"warning: run and run ran in different environments: numpy "
            f"{environment()['numpy']} / 2.3.5; cpu {environment()['cpu']} / another CPU") in err
