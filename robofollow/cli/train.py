"""`robofollow train`: a learned baseline trained on a dataset."""

from __future__ import annotations

import argparse
from pathlib import Path

from robofollow.cli.common import positive
from robofollow.errors import RoboFollowError
from robofollow.learn.options import KINDS, TrainOptions


def add_train(commands) -> None:
    p = commands.add_parser(
        "train", help="train a learned baseline on a dataset (CPU; needs robofollow[train])",
        description="Behaviour cloning from scratch (no downloaded weights) on a LeRobot v2.1 / "
                    "v3.0 dataset written by `robofollow generate`: a small CNN over the "
                    "cameras, the joint state and the instruction (text: its words; form: its "
                    "logical form; blind: nothing) predict chunks of joint targets (L1 loss). "
                    "objects-text and objects-form read the objects observation (every body's "
                    "kind, size, colour and pose: perception removed) instead of the cameras. "
                    "Checkpoints go to OUT every --checkpoint-every steps and at the end; an "
                    "interrupted run continues with --resume. CKPT is then a policy: "
                    "`robofollow eval --policy CKPT`.",
        epilog="examples:\n  robofollow generate --out demos/scene2 --tasks scene2\n  "
               "robofollow train demos/scene2 --policy text --out runs/scene2-text\n  "
               "robofollow train demos/scene2 --policy text --out runs/scene2-text --resume\n"
               "  robofollow eval --policy runs/scene2-text --out runs/eval-text "
               "--scenes scene2", formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("dataset", metavar="DATASET", help="dataset folder")
    p.add_argument("--policy", choices=KINDS,
                   help="what the network reads: the cameras with the instruction's words "
                        "(text), its logical form (form) or nothing (blind), or the objects "
                        "observation with the words or the form (objects-text, objects-form) "
                        f"(default: {TrainOptions.kind})")
    p.add_argument("--out", required=True, metavar="CKPT", help="checkpoint folder (new, "
                                                               "or the one to --resume)")
    p.add_argument("--steps", type=positive, help=f"training steps (default: {TrainOptions.steps})")
    p.add_argument("--batch", type=positive,
                   help=f"samples per step (default: {TrainOptions.batch})")
    p.add_argument("--learning-rate", type=float, metavar="LR",
                   help=f"Adam's peak learning rate (default: {TrainOptions.learning_rate})")
    p.add_argument("--seed", type=int, help="initialisation, order, augmentation and "
                                            f"held-out split (default: {TrainOptions.seed})")
    p.add_argument("--cameras", type=_cameras, metavar="LIST",
                   help=f"comma-separated cameras (default: {','.join(TrainOptions.cameras)})")
    factor = TrainOptions.factor
    p.add_argument("--factor", type=positive, help="shrink camera images by this factor "
                   f"(default: {factor}: 320x240 -> {320 // factor}x{240 // factor})")
    p.add_argument("--shift", type=int, metavar="PX",
                   help=f"random-shift augmentation in pixels (default: {TrainOptions.shift})")
    p.add_argument("--chunk", type=positive,
                   help=f"actions predicted per query (default: {TrainOptions.chunk})")
    p.add_argument("--execute", type=positive,
                   help="actions of each chunk executed before the next query "
                        f"(default: {TrainOptions.execute})")
    p.add_argument("--val-fraction", type=float, metavar="F",
                   help="held-out demonstrations per task for the validation loss "
                        f"(default: {TrainOptions.val_fraction})")
    p.add_argument("--checkpoint-every", type=positive, metavar="N",
                   help=f"steps between checkpoints (default: {TrainOptions.checkpoint_every})")
    p.add_argument("--episodes-per-task", type=positive, metavar="N",
                   help="train on the first N demonstrations of each task (default: all)")
    p.add_argument("--variants-per-task", type=positive, metavar="N",
                   help="train only on episodes worded with one of each task's first N "
                        "instructions (default: all)")
    p.add_argument("--resume", action="store_true",
                   help="continue the run in CKPT with its recorded options")
    p.add_argument("--stop-at", type=positive, metavar="STEP",
                   help="stop (with a checkpoint) at this step; --resume goes on from there "
                        "(splits a long run into sittings; the result is the same)")
    p.add_argument("--no-cache", action="store_true",
                   help="decode the videos without reading or writing the frame cache "
                        "(~/.cache/robofollow/frames)")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p.set_defaults(handler=cmd_train)


def _cameras(text: str) -> tuple[str, ...]:
    from robofollow.sim.cameras import CAMERA_NAMES

    names = tuple(name.strip() for name in text.split(",") if name.strip())
    unknown = [name for name in names if name not in CAMERA_NAMES]
    if unknown or not names:
        raise argparse.ArgumentTypeError(f"cameras are {', '.join(CAMERA_NAMES)}; got {text!r}")
    return names


def cmd_train(args) -> int:
    from dataclasses import fields

    from robofollow.learn.train import (
        default_cache,
        resumed_options,
        train,
    )

    out = Path(args.out)
    tunable = [f.name for f in fields(TrainOptions) if f.name not in ("dataset", "kind")]
    given = {name: getattr(args, name) for name in tunable if getattr(args, name) is not None}
    if args.policy is not None:
        given["kind"] = args.policy
    if args.resume:
        options = resumed_options(out, Path(args.dataset), given)
    else:
        if out.exists() and any(out.iterdir()):
            raise RoboFollowError(f"{out} is not empty; choose a new folder or --resume")
        options = TrainOptions(dataset=str(Path(args.dataset).resolve()), **given)
    cache = None if args.no_cache else default_cache()
    try:
        record = train(options, out, args.resume, progress=not args.quiet, cache=cache,
                       stop_at=args.stop_at)
    except OSError as error:
        raise RoboFollowError(f"cannot write the checkpoint in {out}: {error}") from None
    val = record["val_loss"]
    print(f"{out}: {options.kind} baseline, {record['steps']} of {options.steps} steps, "
          f"loss {record['loss']:.4f}"
          + (f", validation loss {val:.4f}" if val is not None else "")
          + f", {record['wall_seconds'] / 60:.1f} min on {record['cores']} core"
          + ("s" if record["cores"] != 1 else ""))
    print(f"evaluate it: robofollow eval --policy {out} --out runs/{out.name}")
    return 0
