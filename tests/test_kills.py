"""`eval`, `merge` and `report` killed at each of their writes (tests/killed.py: a copy of
the process ends at once, as SIGKILL ends it, just before a file is moved into place or a line is
appended, that line cut in half) leave every file either as it was or as the finished command
leaves it (a results file: whole lines of the finished one, and perhaps a line cut short),
and the same command run again (eval: with --resume, as an interrupted run continues)
finishes the folder exactly as an uninterrupted run does."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from robofollow.cli import main
from tests.killed import KILLED, killed, writes

pytestmark = pytest.mark.slow

RUN = ["--policy", "noop", "--scenes", "scene2", "--levels", "L0", "--sample", "2",
       "--rounds", "1", "--workers", "1", "--quiet"]
RESULTS = "episodes.jsonl"


def _files(folder: Path, scratch: bool = True) -> dict[str, bytes]:
    """The folder's files as a finished command leaves them comparable: a results file's
    records without their timings; no lock, no file being written (*.partial) and, without
    `scratch`, nothing in a merge's scratch folder (.OUT.merging, which only merge reads)."""
    found = {}
    for path in sorted(folder.rglob("*")):
        name = str(path.relative_to(folder))
        if not path.is_file() or path.name == ".lock" or path.name.endswith(".partial"):
            continue
        if not scratch and name.split("/")[0].endswith(".merging"):
            continue
        found[name] = path.read_bytes()
        if path.name == RESULTS:
            found[name] = _untimed(found[name])
    return found


def _untimed(data: bytes) -> bytes:
    """A results file's whole records without their timings, and a line cut short marked."""
    whole, _, cut = data.rpartition(b"\n")
    records = [json.loads(line) for line in whole.split(b"\n") if line]
    for record in records:
        record.pop("seconds")
    return b"".join(json.dumps(r).encode() + b"\n" for r in records) + (b"(cut)" if cut else b"")


def _each_as_before_or_after(killed: dict, before: dict, after: dict, what: str) -> None:
    """Every file, present or not, is as before or as after (a results file: perhaps part of
    the way there)."""
    for name in {*killed, *before, *after}:
        data = killed.get(name)
        if name.endswith(RESULTS) and data is not None and name in after:
            assert after[name].startswith(data.removesuffix(b"(cut)")), (what, name)
            continue
        assert data in (before.get(name), after.get(name)), (what, name)


def _kill_at_every_write(tmp_path: Path, prepare, argv_of, again_of) -> list[str]:
    """Run the command to the end once, then again from the same start for each of its writes,
    killed at it, and once more to finish (again_of); returns the writes. `prepare` makes the
    start in a folder (always the same path, as the pages name their folder) and returns what
    argv_of and again_of take."""
    work = tmp_path / "work"
    target = prepare(work)
    before = _files(work)
    made = writes(work, argv_of(target))
    after = _files(work)
    assert after != before
    for at, write in enumerate(made, start=1):
        shutil.rmtree(work)
        target = prepare(work)
        assert killed(work, at, argv_of(target)) == KILLED, write
        _each_as_before_or_after(_files(work, scratch=False), before, after, f"killed at {write}")
        assert main(again_of(target)) == 0, write
        assert _files(work) == after, f"killed at {write}, then run again"
    return made


def test_eval_killed_at_each_write_resumes_to_the_same_run(tmp_path):
    def prepare(folder: Path) -> Path:
        folder.mkdir()
        return folder / "run"

    writes = _kill_at_every_write(
        tmp_path, prepare, lambda run: ["eval", *RUN, "--out", str(run)],
        lambda run: ["eval", *RUN, "--out", str(run), "--resume"])
    assert [w for w in writes if w.startswith("write")] == [f"write run/{RESULTS}"] * 2


@pytest.fixture(scope="module")
def shards(tmp_path_factory) -> list[Path]:
    root = tmp_path_factory.mktemp("shards")
    found = [root / f"s{index}" for index in (1, 2)]
    for index, shard in enumerate(found, start=1):
        assert main(["eval", *RUN, "--shard", f"{index}/2", "--controls", "empty",
                     "--out", str(shard)]) == 0
    return found


def test_merge_killed_at_each_write_leaves_no_run_or_one_the_same_merge_finishes(tmp_path,
                                                                                  shards):
    def prepare(folder: Path) -> Path:
        folder.mkdir()
        return folder

    def argv(folder: Path) -> list[str]:
        return ["merge", *map(str, shards), "--out", str(folder / "merged")]

    writes = _kill_at_every_write(tmp_path, prepare, argv, argv)
    assert "rename merged" in writes  # (the run moved into place whole)


def test_report_killed_at_each_write_leaves_each_page_old_or_new(tmp_path, shards):
    def prepare(folder: Path) -> Path:
        shutil.copytree(shards[0], folder)
        (folder / "report.md").write_text("an older report\n")
        shutil.rmtree(folder / "figures")
        return folder

    _kill_at_every_write(tmp_path, prepare, lambda run: ["report", str(run)],
                         lambda run: ["report", str(run)])
