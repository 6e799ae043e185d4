"""`robofollow expert`, `score` and `render`: one episode or layout in the simulation."""

from __future__ import annotations

import argparse
import json

from robofollow.cli.common import (
    benchmark_of,
    benchmark_options,
    image_size,
    scene_layout,
)
from robofollow.errors import RoboFollowError


def add_score(commands) -> None:
    p = commands.add_parser(
        "score", help="score a recorded trajectory stage by stage (Intent, Execution)",
        description="Score a saved trajectory (.npz, e.g. from `robofollow expert "
                    "--trajectory`) against a compiled episode: each stage's Intent and "
                    "Execution with the reason, the totals, completion, and what the arms did "
                    "instead. docs/scoring.md explains every stage and threshold.",
        epilog="example:\n  robofollow expert --episode 'scene2/L0/pickup_left_cube#r1' "
               "--trajectory t.npz\n  robofollow score t.npz --episode "
               "'scene2/L0/pickup_right_cube#r1'",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("trajectory", metavar="TRAJECTORY_FILE", help="a saved trajectory (.npz)")
    p.add_argument("--episode", metavar="ID",
                   help="episode id to score against (default: the one the file records)")
    benchmark_options(p)
    p.add_argument("--json", action="store_true", help="print the EpisodeScore as JSON")
    p.set_defaults(handler=cmd_score)


def cmd_score(args) -> int:
    from robofollow.scoring import score_recording
    from robofollow.trajectory import Trajectory

    trajectory = Trajectory.load(args.trajectory)
    episode_id = args.episode or trajectory.meta.get("episode")
    if not episode_id:
        raise RoboFollowError(f"{args.trajectory} does not say which episode it records; "
                              "pass --episode ID")
    benchmark = benchmark_of(args)
    record = benchmark.record(episode_id)
    result = score_recording(benchmark, record, trajectory)
    if args.json:
        print(result.model_dump_json(indent=1))
    else:
        print(f"{record.id}  ({len(trajectory)} frames)")
        print(f"instruction: {record.instruction}\n")
        print(result.table())
    return 0


def add_expert(commands) -> None:
    p = commands.add_parser(
        "expert", help="run the scripted expert on one compiled episode in MuJoCo",
        description="Reset the episode's layout with its seed, execute the expert's compiled "
                    "plan, and score the recording with the oracle. Exit status 1 when the "
                    "oracle does not score the episode complete.",
        epilog="example:\n  robofollow expert --episode 'scene2/L0/pickup_left_cube#r1' "
               "--video out.mp4", formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--episode", required=True, metavar="ID",
                   help="episode id, <scene>/<level>/<task>#r<round> (see episodes/*.jsonl "
                        "of `robofollow compile`)")
    benchmark_options(p)
    p.add_argument("--video", metavar="OUT.mp4",
                   help="write the three cameras side by side as an mp4")
    p.add_argument("--trajectory", metavar="OUT.npz", help="save the recorded trajectory")
    p.add_argument("--image-size", type=image_size, default=(320, 240), metavar="WxH",
                   help="camera image size for --video (default: 320x240)")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object: episode, achieved, intent_score, "
                        "execution_score, reasons, steps, seconds")
    p.set_defaults(handler=cmd_expert)


def cmd_expert(args) -> int:
    from robofollow.sim.cameras import side_by_side
    from robofollow.sim.rollout import run_expert
    from robofollow.sim.simulation import CONTROL_HZ

    benchmark = benchmark_of(args)
    episode = benchmark.record(args.episode)
    width, height = args.image_size
    frames: list = []
    result = run_expert(benchmark, episode,
                        (lambda images: frames.append(side_by_side(images))) if args.video
                        else None, width, height)
    if args.video:
        from robofollow.sim.video import write_video  # (PyAV: only for a video)

        write_video(args.video, frames, CONTROL_HZ)
    if args.trajectory:
        result.trajectory.save(args.trajectory)
    if args.json:
        print(json.dumps(dict(result.summary(), instruction=episode.instruction)))
    else:
        verdict = "achieved" if result.achieved else "NOT achieved"
        print(f"{episode.id}: {verdict} in {result.steps} control steps "
              f"({result.steps / CONTROL_HZ:.1f} s simulated, {result.seconds:.2f} s wall), "
              f"Intent {result.score.intent_score:.2f}, Execution "
              f"{result.score.execution_score:.2f}")
        print(f"  instruction: {episode.instruction}")
        for reason in result.score.failures:
            print(f"  - {reason}")
        for label, path in (("video", args.video), ("trajectory", args.trajectory)):
            if path:
                print(f"  {label}: {path}")
    return 0 if result.achieved else 1


def add_render(commands) -> None:
    p = commands.add_parser(
        "render", help="draw a layout: head camera and a labelled top view",
        description="Build a scene layout in MuJoCo, let it settle, and save the head camera "
                    "image beside a top view with every body's name.")
    p.add_argument("--scene", required=True, help="scene id, e.g. scene1")
    p.add_argument("--layout", help="layout name (default: the scene's first layout)")
    p.add_argument("-o", "--output", required=True, metavar="OUT.png", help="image file")
    p.add_argument("--seed", type=int, help="apply this episode seed's jitter "
                                            "(default: nominal positions)")
    benchmark_options(p)
    p.add_argument("--image-size", type=image_size, default=(640, 480), metavar="WxH",
                   help="size of each of the two views (default: 640x480)")
    p.set_defaults(handler=cmd_render)


def cmd_render(args) -> int:
    from robofollow.sim.picture import layout_picture

    benchmark = benchmark_of(args)
    layout = scene_layout(benchmark, args.scene, args.layout)
    width, height = args.image_size
    layout_picture(benchmark.spec.scenes[args.scene], layout, args.seed, width,
                   height).save(args.output)
    print(f"{args.scene}/{layout} drawn to {args.output}")
    return 0
