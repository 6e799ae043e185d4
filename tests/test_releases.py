"""Benchmark releases: the compiled test set frozen as versioned data. A release loads as the
benchmark it froze, refuses data that do not match its digest, is never overwritten, and every
run names the release (or the working compile) it was made on; a run that names a release this
RoboFollow does not ship is refused by every reader."""

from __future__ import annotations

import gzip
import json
import shutil
from pathlib import Path

import pytest

from robofollow import compiled_cache, release
from robofollow.cli import main
from robofollow.compiler.scene.spec import LEVELS
from robofollow.eval.reports.release_state import runs_under, state_markdown, state_rows
from robofollow.eval.running.run_benchmark import RunBenchmarkError, run_benchmark
from robofollow.eval.running.saved_run import RunReadError, load_options
from robofollow.resources import builtin_specs
from tests.sim_helpers import SHIPPED_RELEASE, benchmark, shipped

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "docs" / "results"


def _copy_release(tmp_path: Path, name: str = SHIPPED_RELEASE) -> Path:
    folder = tmp_path / "releases"
    shutil.copytree(release.releases_dir() / name, folder / name)
    return folder


def test_the_shipped_release_holds_what_its_manifest_counts():
    found, frozen = release.manifest(SHIPPED_RELEASE), shipped()
    assert frozen.release == SHIPPED_RELEASE and frozen.release_digest == found.digest
    assert frozen.spec.digest == found.spec_digest and len(frozen.ids) == found.episodes
    for scene, entry in found.scenes.items():
        for level in LEVELS:
            ids = [e for e in frozen.ids if e.startswith(f"{scene}/{level}/")]
            assert len(ids) == entry.episodes[level]
            assert len({e.partition("#")[0] for e in ids}) == entry.tasks[level]
    episode = frozen.record(frozen.ids[0])
    assert episode.split == found.scenes[episode.scene].split[:16]
    assert set(frozen.training) == {t.label for t in frozen.spec.tasks}


def test_every_shipped_run_resolves_to_a_shipped_release():
    runs = sorted(path.parent for path in RESULTS.glob("**/run.json"))
    assert len(runs) >= 19
    for run in runs:
        options = load_options(run)
        assert run_benchmark(run, options).release == SHIPPED_RELEASE, run


def test_a_frozen_release_loads_as_the_compile_it_froze(tmp_path):
    compiled = benchmark()
    frozen = release.freeze(compiled, "v7", tmp_path)
    loaded, working = release.load("v7", tmp_path), compiled_cache.of(compiled)
    assert (loaded.ids, loaded.lines) == (working.ids, working.lines)
    assert loaded.spec.scenes == compiled.spec.scenes and loaded.training == working.training
    assert frozen.commit is None or len(frozen.commit.split("+")[0]) == 40
    assert frozen.scoring["name"] == "default"
    with gzip.open(tmp_path / "v7" / release.DATA) as data:
        assert data.read().count(b"\n") == len(loaded.ids) + 1


def test_a_release_is_never_overwritten_and_is_named_as_a_version(tmp_path):
    folder = _copy_release(tmp_path)
    before = (folder / SHIPPED_RELEASE / release.DATA).read_bytes()
    with pytest.raises(release.ReleaseError, match="never changes once frozen"):
        release.freeze(benchmark(), SHIPPED_RELEASE, folder)
    assert (folder / SHIPPED_RELEASE / release.DATA).read_bytes() == before
    with pytest.raises(release.ReleaseError, match="expected v followed by a version"):
        release.freeze(benchmark(), "latest", folder)


def test_compile_refuses_to_freeze_over_a_release_before_compiling(tmp_path, capsys):
    assert main(["compile", "--out", str(tmp_path / "build"), "--release",
                 SHIPPED_RELEASE]) == 1
    assert "never changes once frozen" in capsys.readouterr().err
    assert not (tmp_path / "build").exists() or not any((tmp_path / "build").iterdir())
    assert main(["compile", "--out", str(tmp_path / "build"), "--release", "v9",
                 "--no-verify"]) == 2


def test_a_damaged_release_is_refused(tmp_path):
    folder = _copy_release(tmp_path)
    data = folder / SHIPPED_RELEASE / release.DATA
    text = gzip.decompress(data.read_bytes())
    data.write_bytes(gzip.compress(text[:-20] + b"9" + text[-19:]))  # one digit of the last
    with pytest.raises(release.ReleaseError, match="does not match release v1's digest"):
        release.load(SHIPPED_RELEASE, folder)


def test_an_unknown_release_is_named_with_the_shipped_ones(capsys):
    with pytest.raises(release.ReleaseError, match=r"no release 'v1.0' \(releases: v1"):
        release.load("v1.0")
    assert main(["eval", "--policy", "expert", "--out", "unused", "--release", "vv1"]) == 1
    err = capsys.readouterr().err
    assert "no release 'vv1'" in err and "did you mean 'v1'?" in err


def _with_options(tmp_path: Path, source: str, **changes) -> Path:
    run = tmp_path / "run"
    shutil.copytree(RESULTS / source, run)
    options = json.loads((run / "run.json").read_text())
    (run / "run.json").write_text(json.dumps({**options, **changes}))
    return run


@pytest.mark.parametrize("changes,message", [
    ({"release": "v9"}, 'release is "v9", which this RoboFollow does not ship (releases: v1'),
    ({"release": "v1", "release_digest": "0" * 64}, 'release_digest is "000'),
    ({"release_digest": "0" * 64}, "release_digest is given, but no release"),
])
def test_a_run_naming_a_release_that_is_not_here_is_refused_by_every_reader(
        tmp_path, capsys, changes, message):
    run = _with_options(tmp_path, "noop", **changes)
    with pytest.raises(RunReadError, match=message.replace("(", r"\(")):
        load_options(run)
    for command in (["report", str(run)], ["reproduce", str(run)],
                    ["compare", str(run), str(RESULTS / "expert")]):
        assert main(command) == 1, command
        err = capsys.readouterr().err
        assert message in err and "Traceback" not in err and len(err.splitlines()) == 1


def test_a_run_is_read_on_its_own_release(tmp_path):
    run = RESULTS / "noop"
    with pytest.raises(RunBenchmarkError, match="was made on release v1, not v2"):
        run_benchmark(run, load_options(run), "v2")
    gone = _with_options(tmp_path, "noop", specs=str(tmp_path / "gone"))
    with pytest.raises(RunBenchmarkError, match="working compile of .*gone, not a release"):
        run_benchmark(gone, load_options(gone))


def test_the_state_table_agrees_with_the_run_files(monkeypatch):
    """docs/results/state.md is what `robofollow release state docs/results` makes of the
    runs' run.json files; a new current release marks every run on v1 as to redo."""
    monkeypatch.chdir(ROOT)
    folder = Path("docs/results")
    assert (folder / "state.md").read_text() == state_markdown(folder), \
        "regenerate it: robofollow release state docs/results --out docs/results/state.md"
    rows = state_rows(folder)
    assert {row["run"] for row in rows} == {
        run.relative_to(folder).as_posix() for run in runs_under(folder)}
    assert all(row["state"] == "current" for row in rows)
    monkeypatch.setattr(release, "CURRENT", "v2")
    assert all(row["state"] == "on v1, to redo" for row in state_rows(folder))
    assert state_markdown(folder) != (folder / "state.md").read_text()


QUICK = ["--policy", "noop", "--scenes", "scene2", "--levels", "L0", "--sample", "1",
         "--rounds", "1", "--workers", "1", "--quiet"]


def test_a_run_names_its_release_or_its_working_compile(tmp_path):
    """A run on the current release names it and its digest in run.json and in its report; a
    run with --specs names those specs as a working compile, never a release; a run made
    before runs named their release resumes on the release of its specs."""
    on_release, working = tmp_path / "release", tmp_path / "working"
    assert main(["eval", *QUICK, "--out", str(on_release)]) == 0
    assert main(["eval", *QUICK, "--out", str(working), "--specs", str(builtin_specs())]) == 0
    recorded = json.loads((on_release / "run.json").read_text())
    assert recorded["release"] == release.CURRENT and "specs" not in recorded
    assert recorded["release_digest"] == release.manifest(release.CURRENT).digest
    assert (f"Test set: release {release.CURRENT} (digest {recorded['release_digest'][:12]})"
            in (on_release / "report.md").read_text())
    made = json.loads((working / "run.json").read_text())
    assert made["specs"] == str(builtin_specs().resolve()) and "release" not in made
    for page in ("report.md", "report.html"):
        assert "Test set: a working compile of" in (working / page).read_text()
        assert "not a release" in (working / page).read_text()
    before = {k: v for k, v in recorded.items() if k not in ("release", "release_digest")}
    (on_release / "run.json").write_text(json.dumps(before))
    (on_release / "summary.json").unlink()  # (a run still under way)
    assert main(["eval", *QUICK, "--out", str(on_release), "--resume"]) == 0


def test_the_release_command_lists_shows_and_states(capsys, monkeypatch):
    assert main(["release", "list"]) == 0
    listed = capsys.readouterr().out
    found = release.manifest(SHIPPED_RELEASE)
    assert f"* {SHIPPED_RELEASE}" in listed and f"{found.episodes:,}" in listed
    assert main(["release", "show", SHIPPED_RELEASE]) == 0
    shown = capsys.readouterr().out
    assert found.digest in shown and found.scenes["scene1"].split[:12] in shown
    assert main(["release", "show", "v0"]) == 1
    assert "no release 'v0' (releases: v1" in capsys.readouterr().err
    assert main(["release", "diff", "v1", "v1"]) == 2
    monkeypatch.chdir(ROOT)
    assert main(["release", "state", "docs/results"]) == 0
    assert capsys.readouterr().out == (RESULTS / "state.md").read_text()


def test_no_release_is_frozen_into_an_installed_package(tmp_path, monkeypatch):
    installed = tmp_path / "site-packages" / "robofollow" / "releases"
    installed.mkdir(parents=True)
    monkeypatch.setattr(release, "releases_dir", lambda: installed)
    with pytest.raises(release.ReleaseError, match="not a source checkout"):
        release.check_new("v2")
    assert release.check_new("v2", tmp_path) == tmp_path / "v2"  # (a folder named: anywhere)
