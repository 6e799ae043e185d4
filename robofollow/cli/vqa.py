"""`robofollow vqa` and `robofollow vqa score`: scene questions with oracle answers, graded."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from robofollow.cli.common import (
    benchmark_of,
    benchmark_options,
    positive,
    scene_layout,
)
from robofollow.errors import RoboFollowError


def add_vqa(commands) -> None:
    p = commands.add_parser(
        "vqa", help="scene questions with oracle answers: a VLM probe and QA data",
        description="Render a layout's head camera (after jitter, one image per seed) and write "
                    "questions about it whose answers the compiler's grounding decides: colours "
                    "and kinds of objects at relations, leftmost / rightmost, which of two is "
                    "left, the objects of a colour and their sides. Only questions with a "
                    "unique answer are kept. --qa20 writes the paper's 20 Scene 2 questions. "
                    "`robofollow vqa score ANSWERS.jsonl` grades free-text answers.",
        epilog="examples:\n  robofollow vqa --scene scene2 --out vqa/scene2 --count 50\n  "
               "robofollow vqa --qa20 --out vqa/qa20\n  robofollow vqa score answers.jsonl",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    benchmark_options(p)
    p.add_argument("--scene", default="scene2", help="scene id (default: scene2)")
    p.add_argument("--layout", help="layout name (default: the scene's first layout)")
    p.add_argument("--out", metavar="DIR", help="new folder for images and questions")
    p.add_argument("--count", type=positive, default=20, metavar="N",
                   help="number of questions, up to 5 per image (default: 20)")
    p.add_argument("--seed", type=int, default=0,
                   help="jitter seed of the first image; the next images take the next seeds "
                        "(default: 0)")
    p.add_argument("--qa20", action="store_true",
                   help="the paper's QA-20 questions on scene2's default layout at its nominal "
                        "positions (one image; --scene, --layout, --count, --seed unused)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(handler=cmd_vqa)
    actions = p.add_subparsers(dest="vqa_command", metavar="score")
    q = actions.add_parser(
        "score", help="grade free-text answers",
        description="Grade answers (JSON Lines: id and prediction per line, the question's "
                    "expected answer on the line or found by id in the questions file) by "
                    "normalised matching of colours, kinds and sides; prints every mismatch.")
    q.add_argument("answers", metavar="ANSWERS.jsonl")
    q.add_argument("--questions", metavar="FILE",
                   help="questions.jsonl to look expected answers up in (default: the one "
                        "beside ANSWERS.jsonl)")
    q.add_argument("--json", action="store_true", help="print the grades as JSON")
    q.set_defaults(handler=cmd_vqa_score)


def cmd_vqa(args) -> int:
    from robofollow.vqa.paper import LAYOUT, SCENE
    from robofollow.vqa.probe import write_probe

    if not args.out:
        raise RoboFollowError("robofollow vqa: --out DIR is required (or: robofollow vqa score "
                              "ANSWERS.jsonl)")
    out = Path(args.out)
    if out.is_dir() and any(out.iterdir()):
        raise RoboFollowError(f"{out} is not empty; choose a new folder")
    compiled = benchmark_of(args)
    scene, layout = (SCENE, LAYOUT) if args.qa20 else (args.scene,
                                                       scene_layout(compiled, args.scene, args.layout))
    records = write_probe(compiled, scene, layout, out, args.count, args.seed, args.qa20,
                          progress=not args.quiet)
    images = len({r["image"] for r in records})
    print(f"{len(records)} questions on {images} image(s) of {scene}/{layout} in {out} "
          "(questions.jsonl, qa_lerobot.jsonl, qa_sharegpt.json, images/)")
    return 0


def cmd_vqa_score(args) -> int:
    from robofollow.vqa.grade import grade, grade_text

    graded = grade(Path(args.answers), Path(args.questions) if args.questions else None)
    print(json.dumps(graded, indent=1) if args.json else grade_text(graded))
    return 0
