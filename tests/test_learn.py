"""Learned baselines: the dataset reader, the instruction tokens, the network in NumPy and JAX,
training with checkpoints and resume, and the whole chain generate -> train -> eval."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from robofollow.cli import main
from robofollow.eval.statistics.metrics import wilson
from robofollow.learn import checkpoint
from robofollow.learn.demos import downsample, read_demonstrations
from robofollow.learn.model import Architecture, forward, init
from robofollow.learn.options import KINDS
from robofollow.learn.policy import load_baseline
from robofollow.learn.tokens import UNKNOWN, encode, vocabulary, words
from robofollow.learn.train import TrainOptions, train
from robofollow.sim.objects import SHAPE as OBJECTS_SHAPE

TASKS = "pickup_left_cube,pickup_right_cube"


def _generate(folder, fmt: str) -> None:
    assert main(["generate", "--out", str(folder), "--tasks", TASKS, "--episodes-per-task",
                 "2", "--image-size", "80x60", "--format", fmt, "--workers", "1",
                 "--quiet"]) == 0


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    folder = tmp_path_factory.mktemp("demos") / "v21"
    _generate(folder, "lerobot-v2.1")
    return folder


def _options(dataset, **changes) -> TrainOptions:
    base = dict(dataset=str(dataset), steps=4, batch=8, factor=1, checkpoint_every=2,
                val_fraction=0.0)
    return TrainOptions(**{**base, **changes})


def test_downsample_is_an_area_average():
    image = np.arange(4 * 6 * 3, dtype=np.uint8).reshape(4, 6, 3)
    small = downsample(image, 2)
    assert small.shape == (2, 3, 3)
    expected = image.reshape(2, 2, 3, 2, 3).astype(float).mean(axis=(1, 3))
    assert np.array_equal(small, np.floor(expected + 0.5).astype(np.uint8))


def test_tokens_read_words_forms_or_nothing():
    first = "Use your left arm to grasp the red cylinder."
    second = "Pick up the red cylinder with your left arm."
    assert words("text", first)[:3] == ["use", "your", "left"]
    assert words("form", first) == words("form", second)  # paraphrases read alike
    assert words("form", first)[:3] == ["pick", "(", "left"]
    assert words("blind", first) == []
    assert words("form", "Frobnicate the cube.") == ["<unparsed>"]
    vocab = vocabulary("text", [first])
    ids = encode("text", "Use your right arm", vocab)
    assert ids[0] == vocab.index("use") and ids[2] == UNKNOWN and ids[4] == 0


@pytest.mark.parametrize("kind", KINDS)
def test_numpy_and_jax_networks_agree(kind):
    jax = pytest.importorskip("jax")
    from robofollow.learn.train import _jax_conv

    reads_objects = kind.startswith("objects-")
    arch = Architecture(kind, () if reads_objects else ("cam_high", "cam_left_wrist"),
                        (30, 40), 12, chunk=5)
    params = init(arch, seed=3)
    rng = np.random.default_rng(0)
    images = {c: rng.integers(0, 256, (2, 30, 40, 3), dtype=np.uint8) for c in arch.cameras}
    objects = rng.standard_normal((2, *OBJECTS_SHAPE)).astype(np.float32)
    objects[:, :, 0] = np.arange(OBJECTS_SHAPE[0]) < [[5], [7]]  # 5 and 7 bodies present
    objects[:, :, 1:] *= objects[:, :, :1]
    state = rng.standard_normal((2, 14)).astype(np.float32)
    tokens = np.array([[2, 5, 7, 0], [3, 0, 0, 0]], np.int32)
    by_numpy = forward(params, arch, images, state, tokens, objects=objects)
    by_jax = np.asarray(forward(params, arch, images, state, tokens, xp=jax.numpy,
                                conv=_jax_conv, objects=objects))
    assert by_numpy.shape == (2, 5, 14)
    np.testing.assert_allclose(by_numpy, by_jax, rtol=1e-4, atol=1e-4)
    other = tokens.copy()
    other[0, 1] = 9
    changed = forward(params, arch, images, state, other, objects=objects)
    assert np.allclose(changed[1], by_numpy[1])
    assert np.allclose(changed[0], by_numpy[0]) == (kind == "blind")
    if reads_objects:  # the bodies' order carries nothing; a padding row changes nothing
        shuffled = objects.copy()
        shuffled[0, :5] = objects[0, [3, 0, 4, 1, 2]]
        padded = shuffled.copy()
        padded[0, 9, 1:] = 5.0  # under a row marked absent
        for seen in (shuffled, padded):
            np.testing.assert_allclose(forward(params, arch, images, state, tokens,
                                               objects=seen), by_numpy, rtol=1e-5, atol=1e-5)


@pytest.mark.slow
def test_v21_and_v30_datasets_read_the_same(dataset, tmp_path):
    _generate(tmp_path / "v30", "lerobot-v3.0")
    old = read_demonstrations(dataset, ("cam_high",), 2)
    new = read_demonstrations(tmp_path / "v30", ("cam_high",), 2)
    assert old.episodes == new.episodes == 4
    assert old.labels == new.labels and old.instructions == new.instructions
    assert np.array_equal(old.states, new.states) and np.array_equal(old.actions, new.actions)
    assert np.array_equal(old.lengths, new.lengths)
    assert old.images["cam_high"].shape == (int(old.lengths.sum()), 30, 40, 3)
    assert np.array_equal(old.images["cam_high"], new.images["cam_high"])


@pytest.mark.slow
def test_resumed_training_equals_an_uninterrupted_one(dataset, tmp_path):
    whole, split = tmp_path / "whole", tmp_path / "split"
    train(_options(dataset), whole, progress=False)
    first = train(_options(dataset), split, progress=False, stop_at=2)
    assert first["steps"] == 2
    train(_options(dataset), split, resume=True, progress=False)
    a, b = checkpoint.load(whole), checkpoint.load(split)
    assert b.training["steps"] == 4
    assert a.params.keys() == b.params.keys()
    for name in a.params:
        assert np.array_equal(a.params[name], b.params[name]), name
    assert checkpoint.load(whole).params["head.w"].shape == (512, 50 * 14)
    logged = [json.loads(line) for line in (split / "training.jsonl").read_text().splitlines()]
    assert [line["step"] for line in logged] == [2, 4]


@pytest.mark.slow
def test_generate_train_evaluate_every_baseline(dataset, tmp_path):
    for kind in KINDS:
        ckpt, run = tmp_path / kind, tmp_path / f"run-{kind}"
        assert main(["train", str(dataset), "--policy", kind, "--out", str(ckpt), "--steps",
                     "3", "--batch", "8", "--factor", "1", "--val-fraction", "0.5",
                     "--quiet", "--no-cache"]) == 0
        meta = json.loads((ckpt / "policy.json").read_text())
        assert meta["training"]["val_loss"] is not None and meta["training"]["steps"] == 3
        assert main(["eval", "--policy", str(ckpt), "--out", str(run), "--tasks",
                     "scene2/L0/pickup_left_cube", "--rounds", "2", "--workers", "1",
                     "--quiet"]) == 0
        records = [json.loads(line) for line in (run / "episodes.jsonl").read_text()
                   .splitlines()]
        assert len(records) == 2 and all(r["error"] is None for r in records)
        summary = json.loads((run / "summary.json").read_text())
        cell = summary["cells"]["scene2"]["L0"]
        assert cell["ci95"]["IS"][0] <= cell["IS"] <= cell["ci95"]["IS"][1]
        seen = "objects" if kind.startswith("objects-") else "images"
        assert summary["observed"] == sorted(["instruction", "state", seen])
    policy = load_baseline(str(tmp_path / "text"))
    observation = {"state": np.zeros(14), "instruction": "Pick up the left cube.",
                   "images": {"cam_high": np.full((240, 320, 3), 90, np.uint8)}}
    chunk = policy.act(observation)
    assert chunk.shape == (25, 14) and np.array_equal(chunk, policy.act(observation))
    # an objects baseline served over the websocket protocol: the client sends what it reads
    from robofollow.eval.serving.websocket_server import PolicyServer
    from tests.server_helpers import served
    from tests.sim_helpers import benchmark

    with served(PolicyServer(benchmark(), str(tmp_path / "objects-text"))) as port:
        assert main(["eval", "--policy", f"ws://127.0.0.1:{port}", "--out",
                     str(tmp_path / "served"), "--tasks", "scene2/L0/pickup_right_cube",
                     "--rounds", "1", "--workers", "1", "--quiet"]) == 0
    summary = json.loads((tmp_path / "served" / "summary.json").read_text())
    assert summary["observed"] == ["instruction", "objects", "state"]
    assert summary["policy_failures"]["episodes"] == 0


@pytest.mark.slow
def test_training_options_are_checked(dataset, tmp_path, capsys):
    assert main(["train", str(tmp_path / "missing"), "--out", str(tmp_path / "a"),
                 "--quiet"]) == 1
    assert "not a readable dataset file" in capsys.readouterr().err
    for option, value, message in (("--val-fraction", "0.9", "within 0..0.5"),
                                   ("--execute", "60", "more than the 50 actions")):
        assert main(["train", str(dataset), "--out", str(tmp_path / "a"), option, value,
                     "--quiet"]) == 1
        assert message in capsys.readouterr().err
    assert not (tmp_path / "a").exists()
    ckpt = tmp_path / "b"
    assert main(["train", str(dataset), "--out", str(ckpt), "--steps", "2", "--batch", "4",
                 "--factor", "1", "--quiet", "--no-cache"]) == 0
    assert main(["train", str(dataset), "--out", str(ckpt), "--quiet"]) == 1
    assert "not empty" in capsys.readouterr().err
    assert main(["train", str(dataset), "--out", str(ckpt), "--resume", "--batch", "16",
                 "--quiet"]) == 1
    assert "--batch 16 (recorded: 4)" in capsys.readouterr().err
    shutil.copytree(ckpt, tmp_path / "c")
    (tmp_path / "c" / "params.npz").write_bytes(b"not numpy")
    for number, (spec, message) in enumerate((
            ("baseline:nope", "no shipped baseline 'nope'"),
            (str(tmp_path / "c"), "not a readable baseline checkpoint"))):
        assert main(["eval", "--policy", spec, "--out", str(tmp_path / f"run{number}"), "--tasks",
                     "scene2/L0/pickup_left_cube", "--rounds", "1", "--workers", "1",
                     "--quiet"]) == 1
        assert message in capsys.readouterr().err


def test_subsets_of_demonstrations_and_wordings(dataset):
    from robofollow.learn.train import _chosen_episodes

    demos = read_demonstrations(dataset, (), 1)
    assert len(_chosen_episodes(demos, _options(dataset))) == 4
    assert len(_chosen_episodes(demos, _options(dataset, episodes_per_task=1))) == 2
    kept = _chosen_episodes(demos, _options(dataset, variants_per_task=1))
    for label in set(demos.labels):
        assert len({demos.instructions[e] for e in kept if demos.labels[e] == label}) == 1


def test_wilson_intervals():
    assert wilson(0.5, 10) == [23.7, 76.3]
    assert wilson(0.0, 10) == [0.0, 27.8]
    assert wilson(1.0, 160)[1] == 100.0
    low, high = wilson(0.8, 160)
    assert low < 80 < high and high - low < 13


def test_shipped_baselines_load_by_name():
    from robofollow.eval.policies.loading import load_policy
    from robofollow.learn.policy import shipped_names

    assert {"scene2-text", "scene2-blind"} <= set(shipped_names())
    objects = np.zeros(OBJECTS_SHAPE, np.float32)
    objects[:2, 0] = 1.0  # two bodies present
    observation = {"state": np.zeros(14), "instruction": "Pick up the left cube.",
                   "images": {"cam_high": np.full((240, 320, 3), 120, np.uint8)},
                   "objects": objects}
    for name in shipped_names():
        policy = load_policy(f"baseline:{name}")
        chunk = policy.act(observation)
        assert chunk.shape == (policy.ckpt.execute, 14) and np.all(np.isfinite(chunk))
        assert np.array_equal(chunk, policy.act(observation))
        if "images" not in policy.uses:
            continue
        with pytest.raises(ValueError, match="whole multiple"):
            policy.act({**observation, "images": {"cam_high": np.zeros((100, 100, 3),
                                                                       np.uint8)}})
