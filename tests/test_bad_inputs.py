"""Every bad input found by probing the commands that read and write results gives one line
on stderr and exit status 1 (a bad file, or a folder that cannot be used) or 2 (a bad
argument); never a traceback, and nothing written where it should not be."""

from __future__ import annotations

import gzip
import shutil
import zlib
from pathlib import Path

import pytest

from robofollow.cli import main

pytestmark = pytest.mark.slow

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results"
SMALL = ["--policy", "noop", "--scenes", "scene2", "--levels", "L0", "--sample", "2",
         "--rounds", "1", "--workers", "1", "--quiet"]


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    """A small finished run with its full records."""
    out = tmp_path_factory.mktemp("small") / "run"
    assert main(["eval", *SMALL, "--out", str(out)]) == 0
    return out


def _shipped(tmp: Path, name: str = "noop") -> Path:
    run = tmp / name
    shutil.copytree(RESULTS / name, run)
    return run


def _scores(run: Path, change) -> Path:
    """The run with its score file's text changed."""
    path = run / "scores.csv.gz"
    path.write_bytes(gzip.compress(change(gzip.decompress(path.read_bytes()).decode())
                                   .encode(), mtime=0))
    return run


def _field(text: str, column: str, value: str, row: int = 1) -> str:
    lines = text.split("\n")
    header = lines[0].split(",")
    cells = lines[row].split(",")
    cells[header.index(column)] = value
    lines[row] = ",".join(cells)
    return "\n".join(lines)


def _bomb(run: Path) -> Path:
    """A score file that unpacks to 1.5 GB (a few MB packed)."""
    packer = zlib.compressobj(9, zlib.DEFLATED, 31)
    with open(run / "scores.csv.gz", "wb") as f:
        f.write(packer.compress(b"episode,hash,split,motion,intent,execution,complete\n"))
        block = b"0" * (1 << 20)
        f.writelines(packer.compress(block) for _ in range(1536))
        f.write(packer.flush())
    return run


def _run_json(run: Path, change) -> Path:
    path = run / "run.json"
    path.write_text(change(path.read_text()))
    return run


def _linked(small: Path, tmp: Path, name: str) -> Path:
    run = tmp / "linked"
    shutil.copytree(small, run)
    (tmp / "target").write_text("keep")
    (run / name).unlink(missing_ok=True)
    (run / name).symlink_to(tmp / "target")
    return run


def _unfinished_shard(tmp: Path) -> Path:
    run = tmp / "s1"
    assert main(["eval", *SMALL, "--shard", "1/2", "--out", str(run)]) == 0
    (run / "summary.json").unlink()
    return run


def _corrupt_records(small: Path, tmp: Path) -> Path:
    run = tmp / "corrupt"
    shutil.copytree(small, run)
    with open(run / "episodes.jsonl", "a") as f:
        f.write("{not json\n")
    return run


# (name, argv from (tmp_path, small run), exit status, words the one line holds)
CASES = [
    ("resume a shipped run", lambda t, s: ["eval", "--policy", "noop", "--resume", "--quiet",
                                           "--out", str(_shipped(t))], 1, "keeps only its scores"),
    ("export through a linked table1.csv", lambda t, s: [
        "report", str(_linked(s, t, "table1.csv")), "--export", "csv"], 1, "symbolic link"),
    ("export through a linked report.html", lambda t, s: [
        "report", str(_linked(s, t, "report.html"))], 1, "symbolic link"),
    ("resume a shard without its shard", lambda t, s: [
        "eval", *SMALL, "--resume", "--out", str(_unfinished_shard(t))], 1, "shard differ"),
    ("a shard count past every number", lambda t, s: [
        "eval", *SMALL, "--shard", "1/99999999999999999999", "--out", str(t / "r")], 2,
     "expected I/N"),
    ("a shard count past the episodes", lambda t, s: [
        "eval", *SMALL, "--shard", "1/3", "--out", str(t / "r")], 2, "at most 2 shards"),
    ("a shard that is not digits", lambda t, s: [
        "eval", *SMALL, "--shard", "1/²", "--out", str(t / "r")], 2, "expected I/N"),
    ("a server timeout of NaN", lambda t, s: [
        "eval", "--policy", "tcp://127.0.0.1:9?timeout=nan", "--out", str(t / "r")], 1,
     "finite number of seconds"),
    ("an infinite server timeout", lambda t, s: [
        "eval", "--policy", "ws://127.0.0.1:9?timeout=inf", "--out", str(t / "r")], 1,
     "finite number of seconds"),
    ("serve on every interface", lambda t, s: ["serve", "--policy", "noop", "--host", ""], 2,
     "--allow-remote"),
    ("serve on a port past 65535", lambda t, s: ["serve", "--policy", "noop", "--port",
                                                 "70000"], 2, "--port"),
    ("plan for a NaN difference", lambda t, s: ["compare", str(s), "--power", "nan"], 2,
     "--power"),
    ("plan for a tiny difference", lambda t, s: ["compare", str(s), "--power", "1e-300"], 2,
     "--power"),
    ("a comparison into a file", lambda t, s: [
        "report", str(s), str(s), "--out", str(_file(t))], 2, "is a file"),
    ("compare into a file", lambda t, s: ["compare", str(s), str(s), "--out", str(_file(t))], 2,
     "is a file"),
    ("a corrupt run.json", lambda t, s: [
        "report", str(_run_json(_shipped(t), lambda x: x[:40]))], 1, "run.json"),
    ("an extended run.json", lambda t, s: [
        "report", str(_run_json(_shipped(t), lambda x: x.replace('"rounds"', '"extra": 1, '
                                                                '"rounds"')))], 1, "extra"),
    ("a non-numeric intent", lambda t, s: [
        "report", str(_scores(_shipped(t), lambda x: _field(x, "intent", "high")))], 1,
     "intent"),
    ("a non-numeric seed", lambda t, s: [
        "report", str(_scores(_shipped(t), lambda x: _field(x, "seed", "abc")))], 1, "seed"),
    ("an intent of 500", lambda t, s: [
        "report", str(_scores(_shipped(t), lambda x: _field(x, "intent", "500")))], 1,
     "intent"),
    ("a duplicated row", lambda t, s: [
        "report", str(_scores(_shipped(t), lambda x: x.replace(
            "\n", "\n" + x.split("\n")[1] + "\n", 1)))], 1, "episode"),
    ("a level L9", lambda t, s: [
        "report", str(_scores(_shipped(t), lambda x: x.replace("/L0/", "/L9/", 1)))], 1,
     "L9"),
    ("a score file that unpacks to 1.5 GB", lambda t, s: ["report", str(_bomb(_shipped(t)))],
     1, "scores.csv.gz"),
    ("a blank control arm", lambda t, s: ["eval", *SMALL, "--controls", ",", "--out",
                                          str(t / "r")], 2, "blank"),
    ("blank scenes", lambda t, s: ["eval", "--policy", "noop", "--scenes", ",,", "--out",
                                   str(t / "r")], 2, "blank"),
    ("--out with one run", lambda t, s: ["report", str(s), "--out", str(t / "d")], 2, "--out"),
    ("--out with --power", lambda t, s: ["compare", str(s), "--power", "5", "--out",
                                         str(t / "d")], 2, "--out"),
    ("--metric without --power", lambda t, s: ["compare", str(s), str(s), "--metric", "ES"], 2,
     "--metric"),
    ("a corrupt record read by report", lambda t, s: ["report", str(_corrupt_records(s, t))],
     1, "robofollow eval"),
    ("a corrupt record read by merge", lambda t, s: [
        "merge", str(_corrupt_records(s, t)), "--out", str(t / "m")], 1, "robofollow eval"),
]


def _file(tmp: Path) -> Path:
    path = tmp / "a-file"
    path.write_text("mine")
    return path


@pytest.mark.parametrize("name,argv,status,words", CASES, ids=[c[0] for c in CASES])
def test_a_bad_input_gives_one_line(name, argv, status, words, small, tmp_path, capsys):
    args = argv(tmp_path, small)
    capsys.readouterr()
    try:
        found = main(args)
    except SystemExit as stop:  # (argparse's own refusals)
        found = stop.code
    assert found == status
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if not line.startswith("specs: ")]
    assert len(lines) == 1 and words in lines[0] and "Traceback" not in err, err
    if (tmp_path / "target").exists():
        assert (tmp_path / "target").read_text() == "keep"
    if (tmp_path / "a-file").exists():
        assert (tmp_path / "a-file").read_text() == "mine"

