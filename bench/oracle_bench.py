"""Scoring speed: one 500-frame trajectory per action kind, scored by the oracle.

    python bench/oracle_bench.py [--repeats 200] [--frames 500]

For each kind, an expert recording is padded to `--frames` frames (the arms hold still at the
end) and scored `--repeats` times: with the instructed behaviour only, and with the scene's
training behaviours as 'did instead' candidates (as `robofollow score` and evaluation do).
Prints the median time per trajectory and frames per second. Target: < 5 ms per 500 frames.
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time
from functools import partial

import robofollow  # noqa: F401  (before MuJoCo: headless GL default)
from robofollow import release
from robofollow.cli.common import positive
from robofollow.oracle.score import score
from robofollow.scoring import score_recording
from robofollow.sim.rollout import run_expert

KINDS = ["scene1/L0/pickup_yellow_block_2#r1",
         "scene1/L0/place_yellow_block_1_behind_red_cylinder#r1",
         "scene2/L0/push_left_cube_to_red_cylinder#r1",
         "scene2/L0/stack_left_cube_on_red_cylinder#r1",
         "scene2/L0/place_right_cube_in_green_bowl#r1",
         "scene3/L0/l_pick5_around2_to1_short_right#r1",
         "scene4/L0/s41_seq_l_bowl_then_r_green_cylinder#r1",
         "scene4/L0/s41_if_bowl_nonempty_then_l_pick_blue_else_r_stack#r1"]
FRAME_ARRAYS = ("time", "state", "action", "positions", "quaternions", "ee_positions",
                "ee_quaternions", "grasped", "contacts")


def padded(trajectory, frames: int):
    index = [min(i, len(trajectory) - 1) for i in range(frames)]
    return dataclasses.replace(trajectory, **{k: getattr(trajectory, k)[index]
                                              for k in FRAME_ARRAYS})


def median_ms(call, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        began = time.perf_counter()
        call()
        times.append(time.perf_counter() - began)
    return 1000 * statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=positive, default=200)
    parser.add_argument("--frames", type=positive, default=500,
                        help="frames each recording is padded to (at least its length)")
    args = parser.parse_args()
    benchmark = release.benchmark()  # the current release, as `robofollow score` reads it
    print(f"{'episode':<68}{'alone ms':>9}{'+ did-instead ms':>18}{'frames/s':>11}")
    alone_all, full_all = [], []
    for episode_id in KINDS:
        record = benchmark.record(episode_id)
        recording = run_expert(benchmark, record).trajectory
        if len(recording) > args.frames:
            parser.error(f"--frames {args.frames}: {episode_id}'s recording has "
                         f"{len(recording)} frames")
        trajectory = padded(recording, args.frames)
        result = score_recording(benchmark, record, trajectory)
        assert result.complete and result.intent_score == 1.0, (episode_id, result.failures)
        alone = median_ms(partial(score, record.behaviour, trajectory,
                                  benchmark.spec.scenes[record.scene]), args.repeats)
        full = median_ms(partial(score_recording, benchmark, record, trajectory), args.repeats)
        alone_all.append(alone)
        full_all.append(full)
        print(f"{episode_id:<68}{alone:>9.2f}{full:>18.2f}{args.frames / full * 1000:>11.0f}")
    print(f"median over kinds: {statistics.median(alone_all):.2f} ms alone, "
          f"{statistics.median(full_all):.2f} ms with did-instead matching "
          f"({len(benchmark.candidates(record.scene))} candidates in the last scene); worst "
          f"{max(full_all):.2f} ms (target < 5 ms per {args.frames}-frame trajectory)")


if __name__ == "__main__":
    main()
