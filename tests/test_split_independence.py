"""A scene's splits depend on its own spec only: compiled alone, with the other shipped scenes
or beside a new family, a shipped scene has the same tasks, ids, episodes and split digest, and
that digest is the one specs/splits.lock pins. `compile` reports a changed or new split by name
and task counts and verifies those scenes in simulation by default."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from robofollow.benchmark.compiled import clean
from robofollow.benchmark.pipeline import compile_specs
from robofollow.benchmark.rounds import all_episodes, episode_records, ordered_tasks
from robofollow.benchmark.splits_lock import LOCK_FILE, lock_entries
from robofollow.cli import compile as compile_command
from robofollow.cli import main
from robofollow.resources import builtin_specs

FIFTH = Path(__file__).parent / "data" / "extra_scene" / "scene5.rf"
SHIPPED = ("scene1", "scene2", "scene3", "scene4")


def _scene(compiled, scene: str) -> tuple:
    """What a scene's split is: its tasks, episode records and split digest."""
    tasks = [t.model_dump_json() for t in ordered_tasks(compiled) if t.scene == scene]
    records = [r for t in ordered_tasks(compiled) if t.scene == scene
               for r in episode_records(compiled, t)]
    return tasks, records, compiled.split_digests[scene]


def _folder(tmp_path: Path, extra: tuple[Path, ...] = ()) -> Path:
    folder = tmp_path / "specs"
    shutil.copytree(builtin_specs(), folder)
    for path in extra:
        shutil.copy(path, folder / path.name)
    return folder


@pytest.fixture(scope="module")
def together():
    return compile_specs(builtin_specs())


@pytest.fixture(scope="module")
def beside_a_fifth(tmp_path_factory):
    return compile_specs(_folder(tmp_path_factory.mktemp("fifth"), (FIFTH,)))


@pytest.mark.parametrize("scene", SHIPPED)
def test_a_shipped_scene_alone_together_and_beside_a_new_family_is_one_split(
        scene, together, beside_a_fifth):
    alone = compile_specs([builtin_specs() / f"{scene}.rf"])
    assert _scene(alone, scene) == _scene(together, scene) == _scene(beside_a_fifth, scene)


def test_the_new_family_compiles_clean_and_its_episodes_are_its_own(beside_a_fifth):
    assert clean(beside_a_fifth)
    alone = compile_specs([FIFTH])
    assert _scene(alone, "scene5") == _scene(beside_a_fifth, "scene5")
    assert {e.level for e in all_episodes(alone)} == {"L0", "L1", "L2", "L3"}


def test_the_lock_pins_the_shipped_splits(together):
    locked = json.loads((builtin_specs() / LOCK_FILE).read_text())["scenes"]
    assert locked == lock_entries(together)


@pytest.fixture
def verified(monkeypatch) -> list[tuple[str, ...]]:
    """The scenes each `compile` verifies (the simulation itself is tested elsewhere)."""
    calls: list[tuple[str, ...]] = []

    def record(compiled, specs, rounds, workers, scenes):
        calls.append(scenes)
        return True
    monkeypatch.setattr(compile_command, "_verify", record)
    return calls


def test_compile_reports_a_new_scene_and_verifies_it_alone(tmp_path, capsys, verified):
    folder = _folder(tmp_path, (FIFTH,))
    assert main(["compile", str(folder), "--out", str(tmp_path / "out")]) == 0
    out = capsys.readouterr().out
    assert "scene5: new, not in splits.lock (L0 6 L1 12 L2 8 L3 12)" in out
    assert verified == [("scene5",)]
    assert main(["compile", str(folder), "--out", str(tmp_path / "out2"), "--no-verify"]) == 0
    assert verified == [("scene5",)]


def test_compile_reports_a_changed_split_by_name_and_counts(tmp_path, capsys, verified):
    folder = _folder(tmp_path)
    spec = folder / "scene2.rf"
    spec.write_text(spec.read_text().replace("wordings=(referents) max=72",
                                             "wordings=(referents) max=60"))
    assert main(["compile", str(folder), "--out", str(tmp_path / "out")]) == 0
    out = capsys.readouterr().out
    assert "scene2: split CHANGED from splits.lock" in out
    assert "tasks L0 16 L1 48 L2 72 L3 48 -> L0 16 L1 48 L2 60 L3 48" in out
    assert verified == [("scene2",)]
    assert main(["compile", str(folder), "--out", str(tmp_path / "out2"), "--update-lock"]) == 0
    assert "every split is the one" not in capsys.readouterr().out
    assert main(["compile", str(folder), "--out", str(tmp_path / "out3")]) == 0
    assert "every split is the one" in capsys.readouterr().out
    assert verified == [("scene2",), ("scene2",)]


def test_one_shipped_spec_file_is_checked_against_its_folders_lock(tmp_path, capsys, verified):
    assert main(["compile", str(builtin_specs() / "scene2.rf"), "--out",
                 str(tmp_path / "out")]) == 0
    assert "every split is the one" in capsys.readouterr().out and verified == []
    assert main(["compile", str(builtin_specs() / "scene2.rf"), "--out",
                 str(tmp_path / "out2"), "--update-lock"]) == 1
    assert "--update-lock needs a specs folder" in capsys.readouterr().err


def test_the_lock_is_rewritten_only_in_a_specs_folder_that_is_named(tmp_path, capsys,
                                                                     monkeypatch):
    """`--update-lock` without SPECS would rewrite the built-in benchmark's lock (or
    ./specs'): it is refused, and no lock is touched."""
    monkeypatch.chdir(tmp_path)
    lock = builtin_specs() / "splits.lock"
    before = lock.read_bytes()
    assert main(["compile", "--out", str(tmp_path / "out"), "--update-lock"]) == 2
    assert "name the specs folder to pin" in capsys.readouterr().err
    assert lock.read_bytes() == before and not (tmp_path / "out").exists()


def test_an_unverified_split_is_never_pinned(tmp_path, capsys, verified):
    """`--update-lock --no-verify` pinned a changed scene that was never verified: refused
    before anything is compiled, the lock as it was."""
    folder = _folder(tmp_path)
    spec = folder / "scene2.rf"
    spec.write_text(spec.read_text().replace("wordings=(referents) max=72",
                                             "wordings=(referents) max=60"))
    before = (folder / "splits.lock").read_bytes()
    assert main(["compile", str(folder), "--out", str(tmp_path / "out"), "--update-lock",
                 "--no-verify"]) == 2
    assert "--update-lock pins only splits the expert verified" in capsys.readouterr().err
    assert (folder / "splits.lock").read_bytes() == before and verified == []
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("lock,why", [
    ('{"scenes": {"scene2": {"split": "abc", "tasks": "many"}}}', "scene 'scene2': 'tasks' must map levels"),
    ('{"scenes": ["scene2"]}', 'no "scenes" object'),
    (None, "not a regular file"),
])
def test_a_lock_that_is_not_a_split_lock_is_one_line(tmp_path, capsys, lock, why):
    folder = tmp_path / "specs"
    folder.mkdir()
    shutil.copy(builtin_specs() / "scene2.rf", folder)
    if lock is None:
        (folder / LOCK_FILE).mkdir()
    else:
        (folder / LOCK_FILE).write_text(lock)
    assert main(["compile", str(folder), "--out", str(tmp_path / "out"), "--no-verify"]) == 1
    err = capsys.readouterr().err
    assert f"not a split lock ({why}" in err and len(err.splitlines()) == 1, err
