"""The Gymnasium ids (`gymnasium.make`) and the on-disk cache of the compiled benchmark."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

import gymnasium
import pytest
from gymnasium.utils.env_checker import check_env

from robofollow import compiled_cache
from robofollow.resources import builtin_specs
from robofollow.sim import MAX_STEPS
from robofollow.sim.registration import builtin_scenes, env_ids
from tests.cli_helpers import run

# check_env's advice to normalise a Box action space to [-1, 1]: unavoidable, the actions are
# the benchmark's joint targets (radians, gripper 0-1), as policies, the expert and the
# recorded datasets give them
UNAVOIDABLE = ("symmetric and normalized space",)


@pytest.fixture(scope="module", autouse=True)
def cache(tmp_path_factory):
    """A cache folder of the module's own (the user's cache is not touched)."""
    folder = tmp_path_factory.mktemp("cache")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("ROBOFOLLOW_CACHE_DIR", str(folder))
        patch.delenv("ROBOFOLLOW_NO_CACHE", raising=False)
        yield folder / "compiled"


@pytest.fixture(scope="module")
def scene1(tmp_path_factory):
    """A specs folder of one built-in scene (it compiles in a few seconds)."""
    folder = tmp_path_factory.mktemp("specs")
    shutil.copy(builtin_specs() / "scene1.rf", folder)
    return folder


@pytest.fixture(scope="module")
def two_scenes(tmp_path_factory):
    """A specs folder of two built-in scenes, one file each."""
    folder = tmp_path_factory.mktemp("two")
    for name in ("scene1.rf", "scene3.rf"):
        shutil.copy(builtin_specs() / name, folder)
    return folder


def _avoidable(caught: list[warnings.WarningMessage]) -> list[str]:
    return [str(w.message) for w in caught
            if not any(text in str(w.message) for text in UNAVOIDABLE)]


def test_import_registers_the_ids_without_mujoco_or_the_compiler():
    code = ("import sys, robofollow, gymnasium; print(sorted(i for i in gymnasium.registry "
            "if i.startswith('RoboFollow'))); print('mujoco' in sys.modules, "
            "'robofollow.benchmark' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                         text=True).stdout.splitlines()
    assert out == [str(sorted(env_ids())), "False False"]
    assert set(env_ids()) == {"RoboFollow-v0", "RoboFollow-Scene1-v0", "RoboFollow-Scene2-v0",
                              "RoboFollow-Scene3-v0", "RoboFollow-Scene4-v0"}


def test_the_registered_scenes_are_the_compiled_ones():
    assert builtin_scenes() == list(compiled_cache.load(builtin_specs()).spec.scenes)


@pytest.mark.parametrize("env_id", sorted(env_ids()))
def test_make_resets_and_steps_each_id(env_id):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        env = gymnasium.make(env_id, width=64, height=48)
        try:
            obs, info = env.reset(seed=3)
            assert obs["images"]["cam_high"].shape == (48, 64, 3)
            assert info["scene"] == env_ids()[env_id].get("scene", info["scene"])
            obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
            assert (info["step"], reward, terminated, truncated) == (1, 0.0, False, False)
            assert env.spec.max_episode_steps == MAX_STEPS
        finally:
            env.close()
    assert _avoidable(caught) == []


def test_make_passes_its_arguments_to_the_env():
    env = gymnasium.make("RoboFollow-Scene2-v0", level="L1", width=64, height=48)
    try:
        assert {env.reset(seed=seed)[1]["level"] for seed in range(3)} == {"L1"}
        assert all(e.startswith("scene2/L1/") for e in env.unwrapped.choices)
        _, info = env.reset(options={"episode": "scene4/L0/s41_l_pick_blue_sphere#r2"})
        assert info["episode"] == "scene4/L0/s41_l_pick_blue_sphere#r2"
    finally:
        env.close()
    with pytest.raises(ValueError, match="no episodes of scene 'scene9'"):
        gymnasium.make("RoboFollow-v0", scene="scene9")


def test_seeded_resets_draw_the_same_episode():
    env = gymnasium.make("RoboFollow-v0", width=64, height=48).unwrapped
    try:
        first = env.reset(seed=11)[1]["episode"]
        assert env.reset(seed=11)[1]["episode"] == first
        assert len({env.reset(seed=seed)[1]["episode"] for seed in range(5)}) > 1
    finally:
        env.close()


def test_check_env_passes_without_warnings():
    env = gymnasium.make("RoboFollow-v0", width=64, height=48)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            check_env(env.unwrapped)
    finally:
        env.close()
    assert _avoidable(caught) == []


WARM_START = """
import robofollow
from robofollow.sim.env import RoboFollowEnv
env = RoboFollowEnv()
env.reset(seed=0)
env.close()
"""


def test_a_warm_cache_starts_an_env_without_compiling(cache):
    """(How fast: bench/env_start_bench.py.)"""
    compiled_cache.load(builtin_specs())  # warm (written once for the module)
    cached = sorted(cache.iterdir())
    done = subprocess.run([sys.executable, "-c", WARM_START], check=False,
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "compiled" not in done.stderr
    assert sorted(cache.iterdir()) == cached  # read, not compiled again


def _cache_file(cache: Path, spec: Path) -> Path:
    """Where the cache keeps a spec file's compiled part."""
    spec = Path(os.path.realpath(spec))
    return cache / compiled_cache.Entry(spec, spec.read_bytes()).name


def test_a_cached_benchmark_is_read_not_compiled(scene1, monkeypatch, capfd):
    compiled = compiled_cache.load(scene1)
    capfd.readouterr()
    compiled_cache._assemble.cache_clear()  # (the per-process memo: read the file this time)
    monkeypatch.setattr(compiled_cache, "_compile", pytest.fail)
    read = compiled_cache.load(scene1)
    assert read.ids == compiled.ids and read.spec == compiled.spec
    assert read.record(read.ids[-1]) == compiled.record(compiled.ids[-1])
    assert read.candidates("scene1") == compiled.candidates("scene1")
    assert capfd.readouterr().err == ""  # a full hit says nothing


def test_the_cache_holds_what_one_compile_of_the_folder_gives(two_scenes):
    from robofollow.benchmark.pipeline import compile_specs
    from robofollow.benchmark.rounds import all_episodes, episode_records, ordered_tasks
    from robofollow.files import json_line

    cached = compiled_cache.load(two_scenes)
    compiled = compile_specs(two_scenes)
    assert cached.spec == compiled.spec and cached.training == dict(compiled.training)
    assert cached.ids == tuple(episode.id for episode in all_episodes(compiled))
    assert cached.lines == tuple(json_line(record, sort_keys=True).rstrip("\n").encode()
                                 for task in ordered_tasks(compiled)
                                 for record in episode_records(compiled, task))
    assert cached.episodes() == all_episodes(compiled)
    assert cached.task_ids == tuple(task.id for task in ordered_tasks(compiled))
    assert cached.episodes(lambda episode: episode.endswith("#r2")) == [
        episode for episode in all_episodes(compiled) if episode.round == 2]


def test_the_build_holds_what_one_compile_of_the_folder_builds(two_scenes, monkeypatch):
    """What `compile` writes, put together from the spec files compiled alone (the scenes'
    splits, their audits combined, the rendered files), is one compile of the folder's."""
    from robofollow.benchmark import pipeline
    from robofollow.benchmark.render import rendered

    whole = pipeline.compile_timed(two_scenes)[0]
    compiled_cache.build(two_scenes)  # (compiled, or read, and cached)
    compiled_cache._assemble.cache_clear()
    monkeypatch.setattr(compiled_cache, "_compile", pytest.fail)
    compiled, files = compiled_cache.build(two_scenes)  # read from the cache
    assert (compiled.spec, compiled.splits) == (whole.spec, whole.splits)
    assert compiled.training == whole.training and compiled.audit_json == whole.audit_json
    assert files == rendered(whole)


@pytest.mark.parametrize("command", [
    ["eval", "--policy", "noop", "--levels", "L0", "--rounds", "1", "--tasks",
     "scene1/L0/pickup_yellow_block_2", "--quiet", "--out", "{tmp}/run", "--specs", "{specs}"],
    ["generate", "{specs}", "--tasks", "pickup_yellow_block_2", "--episodes-per-task", "1",
     "--image-size", "32x24", "--workers", "1", "--quiet", "--out", "{tmp}/demos"],
    ["vqa", "--scene", "scene1", "--count", "1", "--out", "{tmp}/vqa", "--specs", "{specs}"],
])
def test_commands_read_the_compiled_benchmark_from_the_cache(command, scene1, cache, tmp_path,
                                                             monkeypatch, capsys):
    from robofollow.benchmark import pipeline

    compiled_cache.load(scene1)  # warm
    cached = sorted(cache.iterdir())
    monkeypatch.setattr(pipeline, "_compile", pytest.fail)  # (a compile would fail the test)
    status, _, err = run(capsys, *(part.format(tmp=tmp_path, specs=scene1) for part in command))
    assert status == 0, err
    assert sorted(cache.iterdir()) == cached


def test_compile_reads_unchanged_specs_from_the_cache(two_scenes, tmp_path, cache, capsys,
                                                      monkeypatch):
    """A repeat `compile` compiles nothing and writes the same build; an edited spec compiles
    its own scenes only, and says so."""
    from robofollow.benchmark import pipeline

    specs = shutil.copytree(two_scenes, tmp_path / "specs")
    status, _, err = run(capsys, "compile", str(specs), "--out", str(tmp_path / "first"),
                         "--no-verify")
    assert status == 0 and "compiled scene1 (not cached), scene3 (not cached)" in err
    compiled_cache._assemble.cache_clear()  # (the per-process memos: as a new process)
    pipeline._compile_cached.cache_clear()
    with monkeypatch.context() as patch:
        patch.setattr(pipeline, "_compile", pytest.fail)  # (a compile would fail the test)
        status, _, err = run(capsys, "compile", str(specs), "--out", str(tmp_path / "again"),
                             "--no-verify")
    assert status == 0 and "compiled" not in err
    for path in sorted((tmp_path / "first").rglob("*.*")):
        assert path.read_bytes() == (tmp_path / "again" / path.relative_to(
            tmp_path / "first")).read_bytes(), path
    with open(specs / "scene3.rf", "a", encoding="utf-8") as spec:
        spec.write("\n# changed\n")
    status, _, err = run(capsys, "compile", str(specs), "--out", str(tmp_path / "edited"),
                         "--no-verify")
    assert status == 0 and "compiled scene3 (spec changed), 1 scene from cache" in err


def test_an_edited_spec_compiles_only_its_own_scenes(two_scenes, tmp_path, cache, capfd):
    specs = shutil.copytree(two_scenes, tmp_path / "specs")
    before = compiled_cache.load(specs)
    assert "compiled scene1 (not cached), scene3 (not cached)" in capfd.readouterr().err
    with open(specs / "scene3.rf", "a", encoding="utf-8") as spec:
        spec.write("\n# changed\n")
    assert not _cache_file(cache, specs / "scene3.rf").exists()
    after = compiled_cache.load(specs)
    assert capfd.readouterr().err == "compiled scene3 (spec changed), 1 scene from cache\n"
    assert _cache_file(cache, specs / "scene3.rf").is_file()
    assert after.ids == before.ids and after.lines == before.lines
    assert after.spec.digest != before.spec.digest


def test_scenes_defined_twice_are_compiled_together_and_refused(scene1, tmp_path):
    from robofollow.errors import SpecErrors

    specs = shutil.copytree(scene1, tmp_path / "twice")
    shutil.copy(specs / "scene1.rf", specs / "again.rf")
    with pytest.raises(SpecErrors) as raised:
        compiled_cache.load(specs)
    assert [e.code for e in raised.value.errors] == ["duplicate-scene"]


@pytest.mark.parametrize("damage", ["truncated", "flipped", "garbage", "empty"])
def test_a_corrupt_cache_file_is_compiled_again(scene1, cache, damage):
    expected = compiled_cache.load(scene1)
    path = _cache_file(cache, scene1 / "scene1.rf")
    data = path.read_bytes()
    damaged = {"truncated": data[:len(data) // 2], "garbage": b"\xff\x00not json\n",
               "flipped": data[:-100] + bytes([data[-100] ^ 1]) + data[-99:], "empty": b""}
    path.write_bytes(damaged[damage])
    compiled_cache._assemble.cache_clear()
    loaded = compiled_cache.load(scene1)
    assert loaded.ids == expected.ids and loaded.spec == expected.spec
    assert path.read_bytes() == data  # replaced by a good one


def test_no_cache_writes_nothing(scene1, monkeypatch, tmp_path):
    monkeypatch.setenv("ROBOFOLLOW_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("ROBOFOLLOW_NO_CACHE", "1")
    assert compiled_cache.cache_dir() is None
    assert compiled_cache.load(scene1).ids
    assert not (tmp_path / "cache").exists()


def test_the_key_covers_every_module_the_compiler_runs():
    code = ("import sys, json, robofollow.benchmark; print(json.dumps(sorted(m.__file__ for name, m "
            "in list(sys.modules.items()) if name.startswith('robofollow'))))")
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                         text=True).stdout
    loaded = {os.path.realpath(file) for file in json.loads(out)}
    covered = {os.path.realpath(file) for file in compiled_cache.code_files()}
    package = os.path.dirname(os.path.realpath(compiled_cache.__file__))
    outside = {os.path.join(package, name) for name in
               ("__init__.py", "sim/__init__.py", "sim/registration.py")}  # (not the compile)
    assert loaded - outside <= covered, sorted(loaded - outside - covered)


def test_the_cache_key_covers_what_the_compile_imports_and_nothing_else():
    """A change to the compile's code compiles again; a change to scoring, the simulator or
    the harness does not (their modules are not in the key)."""
    program = ("import sys, robofollow.benchmark.pipeline, robofollow.benchmark.render, "
               "robofollow.compiled_cache; "
               "print('\\n'.join(sys.modules[m].__file__ for m in sys.modules "
               "if m.startswith('robofollow.') and not m.startswith('robofollow.sim')))")
    imported = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True,
                              check=True).stdout.split()
    package = Path(compiled_cache.__file__).resolve().parent
    compile_code = {Path(file).resolve() for file in imported}  # (robofollow.sim: the Gym ids
    # registered by `import robofollow`, which the compile does not use)
    keyed = {path.resolve() for path in compiled_cache.code_files() if path.suffix == ".py"}
    assert compile_code <= keyed
    assert all(path.parent == package / "compiler" for path in keyed - compile_code)
    assert package / "oracle" / "stages.py" not in keyed
