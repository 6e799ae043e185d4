"""`robofollow propose-layouts`: test layouts for a scene, found by search, that keep its L1 and
L3 cells from being passed by guessing."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from robofollow.cli.common import positive, specs_of
from robofollow.errors import RoboFollowError, UsageError, did_you_mean


def add_propose_layouts(commands) -> None:
    p = commands.add_parser(
        "propose-layouts", help="search test layouts that keep a scene's L1/L3 cells from "
                                "being passed by guessing",
        description="Keep the bodies the scene's training tasks handle where its base layout "
                    "puts them, move the other bodies over candidate spots (where they stand "
                    "in any of the scene's layouts, and --spot / --grid), compile every "
                    "candidate as an L1 and L3 layout, and measure per cell its tests, the "
                    "tests whose motion changed, and what the best language-blind guess and "
                    "chance earn. Then select the fewest layouts whose cells meet the bounds, "
                    "or, where none do, the lowest margin over chance any selection reaches "
                    "(the floor the training set sets). Prints the selection and its layout "
                    "statements to paste into the scene. Exit status 1 when the bounds are "
                    "out of reach.")
    p.add_argument("scene", help="the scene to search layouts for, e.g. scene1")
    p.add_argument("--specs", metavar="PATH", help="a spec file or a folder of .rf files "
                                                   "(default: ./specs, else the built-in ones)")
    p.add_argument("--base", metavar="LAYOUT",
                   help="the layout the candidates derive from (default: the scene's first "
                        "training layout)")
    p.add_argument("--spot", action="append", type=_point, default=[], metavar="X,Y",
                   help="a candidate spot in metres (repeatable)")
    p.add_argument("--grid", type=_grid, metavar="X0:X1:STEP,Y0:Y1:STEP",
                   help="candidate spots on a grid, ends included")
    p.add_argument("--keep", action="append", default=[], metavar="BODY",
                   help="a body that stays where the base puts it, besides the handled ones "
                        "(repeatable)")
    p.add_argument("--limit", type=positive, default=1000, metavar="N",
                   help="candidate layouts at most, a seeded sample where there are more "
                        "(default 1000)")
    p.add_argument("--seed", type=int, default=0, help="the sample's seed (default 0)")
    p.add_argument("--margin", type=float, default=15.0, metavar="POINTS",
                   help="the best blind guess at most this many Intent points over chance, "
                        "per cell (default 15)")
    p.add_argument("--max-guess", type=float, default=35.0, metavar="IS",
                   help="the best blind guess's Intent at most this, per cell (default 35)")
    p.add_argument("--min-tests", action="append", type=_level_count, default=[],
                   metavar="[LEVEL=]N", help="tests per cell at least, in both cells or in "
                                             "one (default 40; repeatable: L3=76)")
    p.add_argument("--min-moved", action="append", type=_level_count, default=[],
                   metavar="[LEVEL=]N", help="tests whose motion changed at least, in both "
                                             "cells or in one (default L1=20; repeatable)")
    p.add_argument("--json", metavar="FILE", help="also write every candidate's figures and "
                                                  "the selection as JSON")
    p.set_defaults(handler=cmd_propose_layouts)


def _point(text: str) -> tuple[float, float]:
    try:
        x, y = (float(part) for part in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected X,Y in metres, e.g. 0.1,-0.04; got "
                                         f"{text!r}") from None
    return x, y


def _grid(text: str) -> list[tuple[float, float]]:
    try:
        axes = [[float(v) for v in part.split(":")] for part in text.split(",")]
        (x0, x1, dx), (y0, y1, dy) = axes
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected X0:X1:STEP,Y0:Y1:STEP, e.g. "
                                         f"-0.14:0.10:0.06,-0.18:-0.04:0.07; got {text!r}"
                                         ) from None
    if dx <= 0 or dy <= 0 or x1 < x0 or y1 < y0:
        raise argparse.ArgumentTypeError(f"{text!r}: steps must be positive and ends in order")
    xs = [x0 + i * dx for i in range(int(round((x1 - x0) / dx)) + 1)]
    ys = [y0 + i * dy for i in range(int(round((y1 - y0) / dy)) + 1)]
    return [(round(x, 4), round(y, 4)) for y in ys for x in xs]


def _level_count(text: str) -> dict[str, int]:
    """'N' (both searched levels) or 'L1=N' / 'L3=N'."""
    level, _, count = text.rpartition("=")
    if level not in ("", "L1", "L3") or not count.isdigit():
        raise argparse.ArgumentTypeError(f"expected N, L1=N or L3=N, got {text!r}")
    return {name: int(count) for name in ((level,) if level else ("L1", "L3"))}


def _per_level(given: list[dict[str, int]], default: dict[str, int]) -> dict[str, int]:
    counts = dict(default) if not given else {}
    for entry in given:
        counts.update(entry)
    return counts


def cmd_propose_layouts(args) -> int:
    from robofollow.benchmark.layout_search import Bounds, layout_statements, propose
    from robofollow.benchmark.pipeline import compile_specs

    compiled = compile_specs(specs_of(args))
    scenes = compiled.spec.scenes
    if args.scene not in scenes:
        raise UsageError(f"no scene {args.scene!r} in the specs (scenes: {', '.join(scenes)}) "
                         + did_you_mean(args.scene, scenes))
    scene = scenes[args.scene]
    if args.base is not None and args.base not in scene.layouts:
        raise UsageError(f"scene {args.scene} has no layout {args.base!r} "
                         + did_you_mean(args.base, scene.layouts))
    unknown = [b for b in args.keep if b not in scene.bodies]
    if unknown:
        raise UsageError(f"scene {args.scene} has no body {unknown[0]!r} "
                         + did_you_mean(unknown[0], scene.bodies))
    bounds = Bounds(margin=args.margin, guess=args.max_guess,
                    tests=_per_level(args.min_tests, {"L1": 40, "L3": 40}),
                    moved=_per_level(args.min_moved, {"L1": 20}))
    print(f"searching test layouts for {args.scene}: compiling the candidates ...",
          file=sys.stderr)
    found = propose(compiled.spec, args.scene, compiled.training, args.base,
                    [*args.spot, *(args.grid or [])], args.keep, args.limit, args.seed, bounds,
                    progress=sys.stderr.isatty())
    print(f"{args.scene}: {len(found.candidates)} candidate layouts from {found.base}; kept "
          f"where it puts them: {', '.join(found.kept)}; moved over {len(found.spots)} spots: "
          f"{', '.join(found.moving)}")
    useful = sum(any(c.tests for c in cand.cells.values()) for cand in found.candidates)
    print(f"  {useful} give tests")
    selection = found.selection
    if args.json:
        _write_json(Path(args.json), found, bounds)
    if selection is None:
        print("no selection reaches the tests and moved tests asked per cell: more spots, "
              "or training tasks that pick at more points, are needed")
        return 1
    verdict = "meets the bounds" if selection.meets else (
        f"cannot meet a {args.margin:g}-point margin: the lowest reachable is "
        f"{selection.margin:g} points over chance, whatever the guess (the floor these "
        "spots and this training set allow)")
    print(f"selection: {len(selection.layouts)} layouts, {verdict}")
    for level, cell in selection.cells.items():
        print(f"  {level}: {cell['tests']} tests, {cell['moved']} moved, best blind guess "
              f"{cell['guess_IS']:g} IS, chance {cell['chance_IS']:g}")
    print("\n".join(layout_statements(found.base, found.candidates, selection.layouts)))
    return 0 if selection.meets else 1


def _write_json(path: Path, found, bounds) -> None:
    from dataclasses import asdict

    from robofollow.files import write_json_atomic

    try:
        write_json_atomic(path, {
            "base": found.base, "kept": found.kept, "moving": found.moving,
            "spots": found.spots, "bounds": asdict(bounds),
            "candidates": [asdict(c) for c in found.candidates],
            "selection": None if found.selection is None else asdict(found.selection)})
    except OSError as error:
        raise RoboFollowError(f"cannot write {path}: {error.strerror or error}") from None
