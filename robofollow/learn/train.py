"""`robofollow train`: behaviour cloning of a baseline on a RoboFollow dataset, with JAX on the
CPU (the `robofollow[train]` extra).

Every sample is one frame: the chosen cameras (shrunk, shifted by up to `shift` pixels as
augmentation) or, for the objects kinds, the objects observation (standardised per field), the
joint state and the episode's instruction, with the next CHUNK actions of the
demonstration as the target (the last action repeats past the episode's end: the arms stay
home). Loss: L1 on normalised actions. Adam with a linear warm-up and a cosine decay.

Determinism: parameters start from `seed`; step s draws its batch from epoch s // steps_per_epoch's
seeded permutation and its shifts from (seed, s); so a run resumed from a checkpoint takes
exactly the steps an uninterrupted run takes.
"""

from __future__ import annotations

import json
import os
import queue
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from tqdm import tqdm

from robofollow.files import number_problem
from robofollow.learn import checkpoint
from robofollow.learn.checkpoint import CheckpointError
from robofollow.learn.demos import Demonstrations, read_demonstrations
from robofollow.learn.model import Architecture, forward, init, normalised_objects
from robofollow.learn.options import TrainingError, TrainOptions, reads_objects
from robofollow.learn.tokens import encode, vocabulary

WARMUP = 200  # steps of linear learning-rate warm-up
FINAL_LR = 0.1  # the cosine decay ends at this fraction of the learning rate
VALIDATION_SAMPLES = 1024  # held-out frames scored at each checkpoint
BETAS, EPSILON = (0.9, 0.999), 1e-8
COUNTS = ("steps", "batch", "factor", "chunk", "execute", "checkpoint_every", "episodes_per_task",
          "variants_per_task")  # the options the command line takes as whole numbers from 1


def resumed_options(out: Path, dataset: Path, given: dict) -> TrainOptions:
    """The options recorded in the checkpoint at `out`; options given again must agree."""
    options = _recorded_options(out / "policy.json", checkpoint.load(out).training)
    if Path(options.dataset).resolve() != dataset.resolve():
        raise TrainingError(f"{out} was trained on {options.dataset}, not {dataset}")
    recorded = options.to_dict()
    differing = [f"--{name.replace('_', '-')} {value} (recorded: {recorded[name]})"
                 for name, value in given.items() if recorded.get(name) != value]
    if differing:
        raise TrainingError(f"--resume continues {out} with its recorded options; these "
                            f"differ: {'; '.join(differing)}")
    return options


def _recorded_options(path: Path, training: dict) -> TrainOptions:
    """What a resumed run reads of policy.json's training record: its options, each of its
    type and in range, and the wall time spent; else a CheckpointError naming the field."""
    options = checkpoint.validated(path, TrainOptions, training.get("options"),
                                   "training.options")
    for name in COUNTS:
        value = getattr(options, name)
        if value is not None and value < 1:
            raise CheckpointError(f"{path}: training.options.{name} is {value}, not a whole "
                                  "number from 1")
    try:
        options.check()
    except TrainingError as error:
        raise CheckpointError(f"{path}: training.options: {error}") from None
    problem = number_problem(training.get("wall_seconds"), 0)
    if problem:
        raise CheckpointError(f"{path}: training.wall_seconds {problem}")
    return options


def default_cache() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "robofollow" / "frames"


@dataclass
class Prepared:
    """The dataset as training reads it."""
    demos: Demonstrations
    train_frames: np.ndarray  # global frame indices sampled for training
    val_frames: np.ndarray
    frame_episode: np.ndarray  # [N] episode of each frame
    tokens: np.ndarray  # [E, L] per episode
    vocab: list[str]
    normalization: dict[str, np.ndarray]
    train_episodes: int


def prepare(options: TrainOptions, progress: bool = True, cache: Path | None = None
            ) -> Prepared:
    """The dataset of `options`, read and arranged for training."""
    options.check()
    root = Path(options.dataset)
    with tqdm(desc="decoding", unit="video", disable=not progress) as bar:
        demos = read_demonstrations(root, options.image_cameras, options.factor, bar.update,
                                    cache, objects=reads_objects(options.kind))
    return arrange(demos, options)


def arrange(demos: Demonstrations, options: TrainOptions) -> Prepared:
    """Held-out split, vocabulary, tokens and normalisation of read demonstrations."""
    chosen = _chosen_episodes(demos, options)
    val, train = _split(demos, chosen, options)
    if not len(train):
        raise TrainingError(f"{options.dataset}: no demonstrations left to train on")
    frame_episode = np.repeat(np.arange(demos.episodes), demos.lengths)
    frames = lambda episodes: np.concatenate(  # noqa: E731
        [np.arange(demos.starts[e], demos.starts[e] + demos.lengths[e]) for e in episodes]
        or [np.zeros(0, np.int64)])
    train_frames, val_frames = frames(train), frames(val)
    if len(val_frames) > VALIDATION_SAMPLES:
        val_frames = val_frames[np.linspace(0, len(val_frames) - 1, VALIDATION_SAMPLES)
                                .round().astype(int)]
    vocab = vocabulary(options.kind, [demos.instructions[e] for e in train])
    tokens = np.stack([encode(options.kind, text, vocab) for text in demos.instructions])
    states, actions = demos.states[train_frames], demos.actions[train_frames]
    normalization = {"state_mean": states.mean(0), "state_std": np.maximum(states.std(0), 1e-2),
                     "action_mean": actions.mean(0),
                     "action_std": np.maximum(actions.std(0), 1e-2)}
    if demos.objects is not None:  # each field over the bodies present in the training frames
        rows = demos.objects[train_frames].reshape(-1, demos.objects.shape[-1])
        rows = rows[rows[:, 0] > 0]
        normalization.update(objects_mean=rows.mean(0), objects_std=np.maximum(rows.std(0), 1e-2))
    return Prepared(demos, train_frames, val_frames, frame_episode, tokens, vocab,
                    {k: v.astype(np.float32) for k, v in normalization.items()}, len(train))


def _chosen_episodes(demos: Demonstrations, options: TrainOptions) -> list[int]:
    """The episodes the options keep: the first N demonstrations of each task, and only those
    worded with one of its first M instructions (in the dataset's order)."""
    kept, per_task, wordings = [], {}, {}
    for episode, (label, text) in enumerate(zip(demos.labels, demos.instructions, strict=True)):
        known = wordings.setdefault(label, [])
        if text not in known:
            known.append(text)
        if options.variants_per_task and known.index(text) >= options.variants_per_task:
            continue
        if options.episodes_per_task and per_task.get(label, 0) >= options.episodes_per_task:
            continue
        per_task[label] = per_task.get(label, 0) + 1
        kept.append(episode)
    return kept


def _split(demos: Demonstrations, chosen: list[int], options: TrainOptions
           ) -> tuple[np.ndarray, np.ndarray]:
    """Held-out episodes: a seeded `val_fraction` of each task's (at least one per task with
    three or more demonstrations when the fraction is positive)."""
    rng = np.random.default_rng([options.seed, 7])
    val = []
    by_task: dict[str, list[int]] = {}
    for episode in chosen:
        by_task.setdefault(demos.labels[episode], []).append(episode)
    for label in sorted(by_task):
        episodes = by_task[label]
        count = round(options.val_fraction * len(episodes))
        if options.val_fraction > 0 and len(episodes) >= 3:
            count = max(count, 1)
        val += list(rng.permutation(episodes)[:count])
    train = sorted(set(chosen) - set(val))
    return np.array(sorted(val), np.int64), np.array(train, np.int64)


class Batches:
    """Step s's training batch, a pure function of (seed, s)."""

    def __init__(self, prepared: Prepared, options: TrainOptions):
        self.p, self.o = prepared, options
        self.per_epoch = max(1, len(prepared.train_frames) // options.batch)
        self._epoch, self._order = -1, None

    def frames_of(self, step: int) -> np.ndarray:
        epoch, position = divmod(step, self.per_epoch)
        if epoch != self._epoch:
            rng = np.random.default_rng([self.o.seed, 1, epoch])
            self._epoch, self._order = epoch, rng.permutation(len(self.p.train_frames))
        picked = self._order[position * self.o.batch:(position + 1) * self.o.batch]
        if len(picked) < self.o.batch:  # fewer frames than a batch: draw with repetition
            picked = np.resize(self._order, self.o.batch)
        return self.p.train_frames[picked]

    def batch(self, step: int) -> dict:
        frames = self.frames_of(step)
        rng = np.random.default_rng([self.o.seed, 2, step])
        return assemble(self.p, self.o, frames, rng)


def assemble(prepared: Prepared, options: TrainOptions, frames: np.ndarray,
             rng: np.random.Generator | None) -> dict:
    """Inputs and targets of the given frames (shifted images when `rng` is given)."""
    demos, norm = prepared.demos, prepared.normalization
    episodes = prepared.frame_episode[frames]
    ends = demos.starts[episodes] + demos.lengths[episodes] - 1
    future = np.minimum(frames[:, None] + np.arange(options.chunk), ends[:, None])
    images = {}
    for camera in options.image_cameras:
        stack = np.asarray(demos.images[camera][frames])
        images[camera] = _shifted(stack, options.shift, rng) if rng is not None else stack
    objects = (normalised_objects(demos.objects[frames], norm) if demos.objects is not None
               else np.zeros((len(frames), 0, 0), np.float32))
    return {"images": images, "objects": objects,
            "state": (demos.states[frames] - norm["state_mean"]) / norm["state_std"],
            "tokens": prepared.tokens[episodes],
            "target": (demos.actions[future] - norm["action_mean"]) / norm["action_std"]}


def _shifted(images: np.ndarray, shift: int, rng: np.random.Generator) -> np.ndarray:
    """Each image moved by up to `shift` pixels (edges repeated)."""
    if shift == 0:
        return images
    batch, height, width, _ = images.shape
    padded = np.pad(images, ((0, 0), (shift, shift), (shift, shift), (0, 0)), mode="edge")
    dy, dx = rng.integers(0, 2 * shift + 1, size=(2, batch))
    rows = (dy[:, None] + np.arange(height))[:, :, None]
    columns = (dx[:, None] + np.arange(width))[:, None, :]
    return padded[np.arange(batch)[:, None, None], rows, columns]


def _jax():
    try:
        import jax
        import jax.numpy as jnp
    except ImportError:
        raise TrainingError("training needs JAX: pip install 'robofollow[train]'") from None
    return jax, jnp


def _jax_conv(x, w, stride: int):
    """The network's 'VALID' convolution in JAX (model.numpy_conv's twin)."""
    jax, _ = _jax()
    return jax.lax.conv_general_dilated(x, w, (stride, stride), "VALID",
                                        dimension_numbers=("NHWC", "HWIO", "NHWC"))


def compiled_steps(arch: Architecture, options: TrainOptions, total_steps: int):
    """Jitted (train step, validation loss)."""
    jax, jnp = _jax()

    def loss(params, batch):
        predicted = forward(params, arch, batch["images"], batch["state"], batch["tokens"],
                            xp=jnp, conv=_jax_conv, objects=batch["objects"])
        return jnp.abs(predicted - batch["target"]).mean()

    def rate(step):
        warm = jnp.minimum(1.0, (step + 1) / WARMUP)
        progress = jnp.clip(step / max(1, total_steps), 0.0, 1.0)
        cosine = FINAL_LR + (1 - FINAL_LR) * 0.5 * (1 + jnp.cos(jnp.pi * progress))
        return options.learning_rate * warm * cosine

    def step(params, moments, batch, number):
        value, grads = jax.value_and_grad(loss)(params, batch)
        first, second = moments
        first = {k: BETAS[0] * first[k] + (1 - BETAS[0]) * grads[k] for k in params}
        second = {k: BETAS[1] * second[k] + (1 - BETAS[1]) * grads[k] ** 2 for k in params}
        t = number + 1
        lr = rate(number) * jnp.sqrt(1 - BETAS[1] ** t) / (1 - BETAS[0] ** t)
        params = {k: params[k] - lr * first[k] / (jnp.sqrt(second[k]) + EPSILON)
                  for k in params}
        return params, (first, second), value

    return jax.jit(step), jax.jit(loss)


def train(options: TrainOptions, out: Path, resume: bool = False, progress: bool = True,
          cache: Path | None = None, stop_at: int | None = None) -> dict:
    """Train (or resume) into `out`, up to `stop_at` steps now if given (the rest is left for a
    resumed run); returns the training record of the last checkpoint."""
    _jax()  # before the long decoding: say at once when the training stack is missing
    prepared = prepare(options, progress, cache)
    cameras = options.image_cameras
    arch = Architecture(options.kind, tuple(cameras),
                        prepared.demos.images[cameras[0]].shape[1:3] if cameras else (0, 0),
                        len(prepared.vocab), chunk=options.chunk)
    params, moments, start, spent = _initial_state(arch, options, out, resume)
    step_fn, loss_fn = compiled_steps(arch, options, options.steps)
    batches = Batches(prepared, options)
    record = {"options": options.to_dict(), "episodes": int(prepared.train_episodes),
              "val_episodes": int(len(set(prepared.frame_episode[prepared.val_frames]))),
              "frames": int(len(prepared.train_frames)), "cores": len(os.sched_getaffinity(0)),
              "steps": start, "wall_seconds": spent, "val_loss": None, "loss": None}

    window: list[float] = []  # losses since the last report

    def save(step: int, params, moments) -> None:
        params_np = {k: np.asarray(v) for k, v in params.items()}
        val = _validation(prepared, options, loss_fn, params) if len(prepared.val_frames) \
            else None
        if window:
            record["loss"] = float(np.mean(window))
        record.update(steps=step, val_loss=val)
        ckpt = checkpoint.Checkpoint(arch, prepared.vocab, prepared.normalization,
                                     options.execute, params_np, dict(record))
        optimizer = {"step": np.array(step)}
        for name, moment in zip(("first", "second"), moments, strict=True):
            optimizer.update({f"{name}.{k}": np.asarray(v) for k, v in moment.items()})
        checkpoint.save(out, ckpt, optimizer)
        _log(out, {"step": step, "loss": record["loss"], "val_loss": val,
                   "wall_seconds": round(record["wall_seconds"], 1)})

    until = min(options.steps, stop_at or options.steps)
    prefetch = _Prefetch(batches, start, until)
    began = tick = time.perf_counter()
    bar = tqdm(total=options.steps, initial=start, desc=f"training {options.kind}", unit="step",
               disable=not progress)
    number = start
    try:
        while number < until:
            batch = prefetch.get()
            params, moments, value = step_fn(params, moments, batch, number)
            number += 1
            window.append(float(value))
            record["wall_seconds"] = spent + time.perf_counter() - began
            if number % 50 == 0 or number == options.steps:
                record["loss"] = float(np.mean(window))
                now = time.perf_counter()
                rate = options.batch * len(window) / max(1e-9, now - tick)
                bar.set_postfix(loss=f"{record['loss']:.4f}", val=_fmt(record["val_loss"]),
                                samples_s=f"{rate:.0f}")
                window.clear()
                tick = now
            bar.update(1)
            if number % options.checkpoint_every == 0 or number == until:
                save(number, params, moments)
    except KeyboardInterrupt:
        save(number, params, moments)
        bar.close()
        raise TrainingError(f"interrupted at step {number}; checkpoint saved in {out} "
                            "(continue with --resume)") from None
    finally:
        prefetch.stop()
    bar.close()
    return record


def _initial_state(arch: Architecture, options: TrainOptions, out: Path, resume: bool):
    """(parameters, Adam moments, first step, wall seconds spent): fresh, or from `out`."""
    if resume:
        previous, state = checkpoint.load(out), checkpoint.load_optimizer(out)
        moments = tuple({k.split(".", 1)[1]: state[k] for k in state if k.startswith(f"{name}.")}
                        for name in ("first", "second"))
        return (previous.params, moments, int(state["step"]),
                float(previous.training["wall_seconds"]))
    params = init(arch, options.seed)
    moments = tuple({k: np.zeros_like(v) for k, v in params.items()} for _ in range(2))
    out.mkdir(parents=True, exist_ok=True)
    (out / "training.jsonl").write_text("")
    return params, moments, 0, 0.0


def _fmt(value) -> str:
    return "-" if value is None else f"{value:.4f}"


def _validation(prepared: Prepared, options: TrainOptions, loss_fn, params) -> float:
    losses, weights = [], []
    for begin in range(0, len(prepared.val_frames), options.batch):
        frames = prepared.val_frames[begin:begin + options.batch]
        losses.append(float(loss_fn(params, assemble(prepared, options, frames, None))))
        weights.append(len(frames))
    return float(np.average(losses, weights=weights))


def _log(out: Path, line: dict) -> None:
    with open(out / "training.jsonl", "a") as file:
        file.write(json.dumps(line) + "\n")


class _Prefetch:
    """Assembles the next batches on a thread while the current step runs."""

    def __init__(self, batches: Batches, start: int, stop: int, depth: int = 3):
        self._queue: queue.Queue = queue.Queue(depth)
        self._stopped = threading.Event()

        def work() -> None:
            for number in range(start, stop):
                try:
                    item = batches.batch(number)
                except Exception as error:  # handed to the training loop, which raises it
                    item = error
                while not self._stopped.is_set():
                    try:
                        self._queue.put(item, timeout=0.1)
                        break
                    except queue.Full:
                        continue
                if self._stopped.is_set():
                    return

        self._thread = threading.Thread(target=work, daemon=True)
        self._thread.start()

    def get(self) -> dict:
        item = self._queue.get()
        if isinstance(item, Exception):
            raise item
        return item

    def stop(self) -> None:
        self._stopped.set()
        self._thread.join()
