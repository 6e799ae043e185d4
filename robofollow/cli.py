"""`robofollow` command line: thin wrappers around library functions."""

from __future__ import annotations

import argparse
import difflib
import io
import json
import os
import sys
from importlib.metadata import version
from pathlib import Path

from robofollow.compiler import lf
from robofollow.compiler.notation import notation
from robofollow.compiler.parser import parse
from robofollow.compiler.realize import STYLES, realize
from robofollow.compiler.spec import LEVELS
from robofollow.files import json_line
from robofollow.data.jobs import FORMATS, INSTRUCTION_MODES
from robofollow.errors import InstructionError, RoboFollowError
from robofollow.resources import builtin_specs
from robofollow.workers import EXECUTORS

_PARSE_EXAMPLES = """\
examples:
  robofollow parse "Use your left arm to pick up the block to the right of the red ball."
  robofollow parse --json "Push the leftmost cube towards the larger red object."
  robofollow parse --style trailing "If the bowl is empty, pick up the red sphere."
  printf 'Pick up the red cube.\\nPick up the cube.\\n' | robofollow parse -

With '-', each line of standard input is one instruction and each output line is one JSON
object: {"text": ..., "lf": {...}} or {"text": ..., "error": {"type", "column", "message"}}.
The exit status is 1 when any instruction fails to parse.
"""


_SPECS_DEFAULT = "./specs when this folder has one, else the built-in benchmark"


def specs_of(args) -> Path:
    """The specs a command reads: as given; else ./specs when the current folder has one;
    else the benchmark's own, installed with the package. Said on stderr when not given."""
    if args.specs is not None:
        return Path(args.specs)
    if Path("specs").is_dir():
        print("specs: ./specs (this folder's; --specs chooses others)", file=sys.stderr)
        return Path("specs")
    path = builtin_specs()
    print(f"specs: the built-in benchmark ({path})", file=sys.stderr)
    return path


def _parse_one(text: str, args) -> int:
    try:
        instruction = parse(text)
    except InstructionError as error:
        print(error.render(), file=sys.stderr)
        return 1
    if args.json:
        print(lf.to_json(instruction, indent=2))
    else:
        print(f"lf       {notation(instruction)}")
        print(f"english  {realize(instruction, args.style)}")
    return 0


def _parse_stream(stream, out) -> int:
    """One output record per input line, blank lines included (an 'empty' error)."""
    status = 0
    for line in stream:
        text = line.removesuffix("\n").removesuffix("\r")
        try:
            record = {"text": text, "lf": parse(text).model_dump(mode="json")}
        except InstructionError as error:
            record, status = {"text": text, "error": error.to_dict()}, 1
        out.write(json_line(record))
        out.flush()
    return status


def _stdin_lines():
    """Standard input as text split at '\\n' only (a stray '\\r' stays in its line); bytes
    that are not UTF-8 become U+FFFD (an unknown word)."""
    if hasattr(sys.stdin, "buffer"):
        return io.TextIOWrapper(sys.stdin.buffer, encoding="utf-8", errors="replace",
                                newline="\n")
    return sys.stdin


def cmd_parse(args) -> int:
    if args.text == "-":
        return _parse_stream(_stdin_lines(), sys.stdout)
    return _parse_one(args.text, args)


def cmd_compile(args) -> int:
    from robofollow.build.output import check_out, write
    from robofollow.build.pipeline import clean, compile_specs
    from robofollow.build.summary import summary

    check_out(Path(args.out))  # before the work: an --out that cannot take the build is refused
    specs = specs_of(args)
    compiled = compile_specs(specs)
    changed = write(compiled, Path(args.out))
    print(summary(compiled, changed), end="")
    print(f"written to {args.out}")
    verified = _verify(compiled, specs, args.verify, args.workers) if args.verify else True
    return 0 if clean(compiled) and verified else 1


def _verify(compiled, specs: Path, rounds: int, workers: int | None) -> bool:
    """The expert on the first `rounds` rounds of every test task; failures listed."""
    from robofollow.build.rounds import all_episodes
    from robofollow.eval.verify import run_expert_episodes

    episodes = [e for e in all_episodes(compiled) if e.round <= rounds]
    print(f"\nverifying: the expert on {len(episodes)} episodes ({rounds} round"
          f"{'s' if rounds > 1 else ''} of every test task) in simulation")
    results = run_expert_episodes(specs, episodes, workers or os.cpu_count() or 1)
    failures = [r for r in results if not r["full"]]
    print(f"the expert scored in full on {len(results) - len(failures)} of {len(results)}; "
          f"failures: {len(failures) or 'none'}")
    for failure in failures:
        print(f"  {failure['episode']}: {'; '.join(failure['reasons'])}")
    return not failures


def cmd_audit(args) -> int:
    from robofollow.build.pipeline import clean, compile_specs
    from robofollow.build.summary import summary
    from robofollow.files import write_jsonl
    from robofollow.audit.task_list import audit_task_list, read_task_list, task_list

    compiled = compile_specs(specs_of(args))
    if args.export_tasks:
        try:
            write_jsonl(Path(args.export_tasks), task_list(compiled.splits))
        except OSError as error:
            raise RoboFollowError(f"cannot write {args.export_tasks}: "
                                  f"{error.strerror or error}") from None
        print(f"wrote {len(compiled.splits.tasks)} test tasks to {args.export_tasks}",
              file=sys.stderr)
    report, listed = compiled.report, None
    if args.tasks:
        listed = audit_task_list(compiled.spec, compiled.training,
                                 read_task_list(Path(args.tasks)))
        report = {**report, **listed}
    if args.json:
        print(json.dumps(report, indent=1, sort_keys=True))
    else:
        print(summary(compiled), end="")
        if listed is not None:
            print(_task_list_text(args.tasks, listed), end="")
    return 0 if clean(compiled) and not (listed and listed["findings"]) else 1


def _task_list_text(path: str, listed: dict) -> str:
    """Findings grouped by kind, with counts."""
    from robofollow.audit.task_list import FINDING_KINDS

    findings = listed["findings"]
    lines = ["", f"task list {path}: {listed['checked']} tasks checked, "
                 f"{len(findings) or 'no'} finding{'' if len(findings) == 1 else 's'}"]
    for kind in FINDING_KINDS:
        items = [f for f in findings if f["kind"] == kind]
        if items:
            lines.append(f"{kind}: {len(items)}")
            lines += [f"  {f['id']}: {f['message']}" for f in items]
    return "\n".join(lines) + "\n"


def _positive(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


def _seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, got {text!r}") from None
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"must be a positive number of seconds, got {text}")
    return value


def _cameras(text: str) -> tuple[str, ...]:
    from robofollow.sim.cameras import CAMERA_NAMES

    names = tuple(name.strip() for name in text.split(",") if name.strip())
    unknown = [name for name in names if name not in CAMERA_NAMES]
    if unknown or not names:
        raise argparse.ArgumentTypeError(f"cameras are {', '.join(CAMERA_NAMES)}; got {text!r}")
    return names


def _size(text: str) -> tuple[int, int]:
    try:
        width, height = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT such as 320x240, got {text!r}") from None
    if not (16 <= width <= 4096 and 16 <= height <= 4096):
        raise argparse.ArgumentTypeError(f"image size {text} is out of range (16..4096)")
    return width, height


def cmd_expert(args) -> int:
    from robofollow.build.pipeline import compile_specs
    from robofollow.build.rounds import find_episode
    from robofollow.sim.cameras import side_by_side
    from robofollow.sim.rollout import run_expert
    from robofollow.sim.simulation import CONTROL_HZ
    from robofollow.sim.video import write_video

    compiled = compile_specs(specs_of(args))
    episode = find_episode(compiled, args.episode)
    width, height = args.image_size
    frames: list = []
    result = run_expert(compiled, episode,
                        (lambda images: frames.append(side_by_side(images))) if args.video
                        else None, width, height)
    if args.video:
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


def cmd_score(args) -> int:
    from robofollow.build.pipeline import compile_specs
    from robofollow.build.rounds import find_episode
    from robofollow.scoring import score_recording
    from robofollow.trajectory import Trajectory

    trajectory = Trajectory.load(args.trajectory)
    episode_id = args.episode or trajectory.meta.get("episode")
    if not episode_id:
        raise RoboFollowError(f"{args.trajectory} does not say which episode it records; "
                              "pass --episode ID")
    compiled = compile_specs(specs_of(args))
    record = find_episode(compiled, episode_id)
    result = score_recording(compiled, record, trajectory)
    if args.json:
        print(result.model_dump_json(indent=1))
    else:
        print(f"{record.id}  ({len(trajectory)} frames)")
        print(f"instruction: {record.instruction}\n")
        print(result.table())
    return 0


def cmd_render(args) -> int:
    from robofollow.build.pipeline import compile_specs
    from robofollow.sim.picture import layout_picture

    compiled = compile_specs(specs_of(args))
    layout = _layout(compiled, args.scene, args.layout)
    width, height = args.image_size
    layout_picture(compiled.spec.scenes[args.scene], layout, args.seed, width,
                   height).save(args.output)
    print(f"{args.scene}/{layout} drawn to {args.output}")
    return 0


def _layout(compiled, scene: str, layout: str | None) -> str:
    """A scene's layout by name (default: its first), checked."""
    scenes = compiled.spec.scenes
    if scene not in scenes:
        raise RoboFollowError(f"no scene {scene!r}; scenes: {', '.join(scenes)}")
    layouts = scenes[scene].layouts
    layout = layout or next(iter(layouts))
    if layout not in layouts:
        raise RoboFollowError(f"scene {scene} has no layout {layout!r}; layouts: "
                              f"{', '.join(layouts)}")
    return layout


def cmd_vqa(args) -> int:
    from robofollow.build.pipeline import compile_specs
    from robofollow.vqa.paper import LAYOUT, SCENE
    from robofollow.vqa.probe import write_probe

    if not args.out:
        raise RoboFollowError("robofollow vqa: --out DIR is required (or: robofollow vqa score "
                              "ANSWERS.jsonl)")
    out = Path(args.out)
    if out.is_dir() and any(out.iterdir()):
        raise RoboFollowError(f"{out} is not empty; choose a new folder")
    compiled = compile_specs(specs_of(args))
    scene, layout = (SCENE, LAYOUT) if args.qa20 else (args.scene,
                                                       _layout(compiled, args.scene, args.layout))
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


def cmd_generate(args) -> int:
    from robofollow.build.pipeline import compile_specs
    from robofollow.data.generate import generate
    from robofollow.data.jobs import select_tasks
    from robofollow.data.units import Options

    specs = specs_of(args)
    compiled = compile_specs(specs)
    width, height = args.image_size
    tasks = select_tasks(compiled, [t for t in (args.tasks or "").split(",") if t.strip()])
    options = Options(args.format, args.episodes_per_task, tuple(tasks), width, height,
                      args.instructions, compiled.spec.digest)
    try:
        result = generate(compiled, Path(args.out), options, args.workers, args.resume,
                          progress=not args.quiet)
    except KeyboardInterrupt:
        return _interrupted("demonstrations", args.out)
    except OSError as error:
        raise RoboFollowError(f"cannot write the dataset in {args.out}: {error}") from None
    if result.already_complete:
        print(f"{args.out} is already complete: {result.episodes} episodes")
    else:
        print(f"{args.out}: {result.episodes} episodes ({args.format}) from "
              f"{result.demonstrations} demonstrations of {len(tasks)} tasks, "
              f"{result.recorded} recorded now, {result.discarded} attempts discarded, "
              f"{result.seconds / 60:.1f} min")
    for failure in result.failed:
        print(f"  failed: {failure['failed']}", file=sys.stderr)
    return 1 if result.failed else 0


def cmd_train(args) -> int:
    from dataclasses import fields

    from robofollow.learn.train import (
        TrainOptions,
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


def cmd_dataset_check(args) -> int:
    from robofollow.data.check import check

    report = check(Path(args.dataset))
    print(json.dumps(report.to_dict(), indent=1) if args.json else report.render())
    return 0 if report.ok else 1


def cmd_eval(args) -> int:
    from robofollow.build.pipeline import compile_specs
    from robofollow.eval.deadline import DEFAULT_POLICY_TIMEOUT
    from robofollow.eval.loading import with_privileged
    from robofollow.eval.policy_kind import is_server
    from robofollow.eval.report import write_report
    from robofollow.eval.runner import EvalOptions, evaluate, failures_text
    from robofollow.eval.tables import table_text

    compiled = compile_specs(specs_of(args))
    scenes = _names(args.scenes, list(compiled.spec.scenes), "scene")
    levels = _names(args.levels, list(LEVELS), "level")
    known_tasks = [t.id for t in compiled.splits.tasks]
    tasks = _names(args.tasks, known_tasks, "task") if args.tasks else []
    if args.policy_timeout is not None and is_server(args.policy):
        raise RoboFollowError("--policy-timeout limits in-process policies; a server takes "
                              "its own: --policy URL?timeout=S&retries=N")
    policy = with_privileged(args.policy) if args.allow_privileged else args.policy
    options = EvalOptions(policy, tuple(scenes), tuple(levels), args.rounds,
                          args.instruction_mode, args.video, compiled.spec.digest, tuple(tasks),
                          args.sample, args.policy_timeout if args.policy_timeout is not None
                          else None if is_server(args.policy) else DEFAULT_POLICY_TIMEOUT)
    try:
        result = evaluate(compiled, Path(args.out), options, args.workers, args.resume,
                          progress=not args.quiet, executor=args.executor,
                          drop_corrupt=args.drop_corrupt)
    except KeyboardInterrupt:
        return _interrupted("episodes", args.out)
    try:
        markdown, _ = write_report(Path(args.out))
    except OSError as error:
        raise RoboFollowError(f"cannot write the report in {args.out}: "
                              f"{error.strerror or error} (the results are kept; "
                              f"robofollow report {args.out} writes it)") from None
    print(f"{args.policy} ({args.instruction_mode} instructions), {args.out}:")
    print(table_text(result))
    failures = failures_text(result)
    if failures:
        print(failures)
    print(f"report: {markdown} (and .html)")
    return 3 if failures else 0


def cmd_report(args) -> int:
    from robofollow.eval.report import comparison, write_report

    runs = [Path(run) for run in args.runs]
    if len(runs) > 2:
        raise RoboFollowError("report takes one run, or two to compare")
    if len(runs) == 1:
        markdown, html = write_report(runs[0])
        print(f"wrote {markdown} and {html}")
        return 0
    text = comparison(runs)
    if args.out:
        Path(args.out).write_text(text, encoding="utf-8")
        print(f"wrote {args.out}")
    else:
        print(text)
    return 0


def _interrupted(what: str, out: str) -> int:
    print(f"\ninterrupted: the finished {what} are kept in {out}; run the same command with "
          "--resume to continue", file=sys.stderr)
    return 130


def _names(text: str | None, known: list[str], what: str) -> list[str]:
    """A comma-separated selection of known names (all of them when empty)."""
    chosen = [n.strip() for n in (text or "").split(",") if n.strip()] or known
    unknown = [n for n in chosen if n not in known]
    if unknown:
        hints = [m for n in unknown for m in difflib.get_close_matches(n, known, n=3)]
        listed = (f"did you mean {', '.join(dict.fromkeys(hints))}?" if hints and len(known) > 12
                  else f"known: {', '.join(known[:12])}{' …' if len(known) > 12 else ''}")
        raise RoboFollowError(f"unknown {what} {', '.join(unknown)}; {listed}")
    return [n for n in known if n in chosen]


def cmd_serve(args) -> int:
    import logging

    from robofollow.build.pipeline import compile_specs
    from robofollow.eval.serving import ServerLimits
    from robofollow.eval.tcp_server import TcpPolicyServer
    from robofollow.eval.websocket_server import PolicyServer

    server_class, scheme = ((TcpPolicyServer, "tcp") if args.protocol == "tcp"
                            else (PolicyServer, "ws"))
    limits = ServerLimits(args.max_message, args.idle_timeout, args.max_clients)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s: %(message)s")
    server = server_class(compile_specs(specs_of(args)), args.policy, limits)

    def listening(_) -> None:  # only now can a client connect
        print(f"serving {args.policy} on {scheme}://{args.host}:{args.port} (Ctrl-C stops; "
              f"health check: http://{args.host}:{args.port}/healthz)", flush=True)
        if "privileged" in server.pool.uses:
            print(f"note: {args.policy} is a reference policy reading privileged observations: "
                  "only `robofollow eval --allow-privileged` clients can drive it; other "
                  "clients (openpi's) get an error reply saying so", file=sys.stderr, flush=True)

    try:
        server.serve_forever(args.host, args.port, ready=listening)
    except KeyboardInterrupt:
        pass  # Ctrl-C is how a server is stopped
    except OSError as error:  # e.g. the port is taken, or no such address here
        raise RoboFollowError(f"cannot listen on {args.host}:{args.port}: {error}") from None
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="robofollow",
        description="RoboFollow: measure whether robot policies really follow language "
                    "instructions.")
    parser.add_argument("--version", action="version",
                        version=f"robofollow {version('robofollow')}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    p = commands.add_parser(
        "parse", help="parse instructions into canonical logical forms",
        description="Parse an instruction into its canonical logical form and say it back in "
                    "English.", epilog=_PARSE_EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("text", metavar="TEXT", help="the instruction, or '-' to read one per line "
                                                "from standard input (JSON lines out)")
    p.add_argument("--json", action="store_true", help="print the logical form as JSON")
    p.add_argument("--style", choices=sorted(STYLES), default="plain",
                   help="paraphrase style of the English line (default: plain)")
    p.set_defaults(handler=cmd_parse)

    p = commands.add_parser(
        "compile", help="compile the specs into validated L0-L3 splits",
        description="Load the .rf specs, check every training task, generate the L0-L3 "
                    "splits from the split rules, audit them, and write the episodes, goal "
                    "DAGs, rejected candidates, audit.json and summary.txt. Exit status 1 on "
                    "a bad spec or any audit finding.")
    p.add_argument("specs", nargs="?", help="a spec file or a folder of .rf files "
                                            "(default: " + _SPECS_DEFAULT + ")")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder")
    p.add_argument("--verify", type=int, nargs="?", const=1, default=0, metavar="ROUNDS",
                   help="then run the scripted expert on the first ROUNDS rounds (default 1) "
                        "of every test task in simulation and list the episodes it does not "
                        "score in full, with the stages lost (exit status 1 if any)")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="simulation workers for --verify (default: the number of CPUs)")
    p.set_defaults(handler=cmd_compile)

    p = commands.add_parser(
        "audit", help="audit the splits, or any task list: entropy, leakage, repertoire, "
                      "ambiguity",
        description="Compile the specs in memory and report the audit. With --tasks, also "
                    "audit a task list (JSON Lines: id, scene, level, layout, instruction, "
                    "optional expect) against the specs' scenes and training tasks: parse "
                    "errors, missing or ambiguous referents (also at the jitter extremes), "
                    "expectation mismatches, behaviours outside the training repertoire, "
                    "leakage and level inconsistencies. Exit status 1 on a bad spec or any "
                    "finding.")
    p.add_argument("specs", nargs="?", help="a spec file or a folder of .rf files "
                                            "(default: " + _SPECS_DEFAULT + ")")
    p.add_argument("--tasks", metavar="FILE.jsonl", help="a task list to audit")
    p.add_argument("--export-tasks", metavar="FILE.jsonl",
                   help="write the compiled test tasks as a task list (expect = the compiled "
                        "behaviour)")
    p.add_argument("--json", action="store_true",
                   help="print the audit as one JSON object (with --tasks: plus findings and "
                        "checked)")
    p.set_defaults(handler=cmd_audit)

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
    p.add_argument("--specs", help="spec file or folder (default: " + _SPECS_DEFAULT + ")")
    p.add_argument("--json", action="store_true", help="print the EpisodeScore as JSON")
    p.set_defaults(handler=cmd_score)

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
    p.add_argument("--specs", help="spec file or folder (default: " + _SPECS_DEFAULT + ")")
    p.add_argument("--video", metavar="OUT.mp4",
                   help="write the three cameras side by side as an mp4")
    p.add_argument("--trajectory", metavar="OUT.npz", help="save the recorded trajectory")
    p.add_argument("--image-size", type=_size, default=(320, 240), metavar="WxH",
                   help="camera image size for --video (default: 320x240)")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object: episode, achieved, intent_score, "
                        "execution_score, reasons, steps, seconds")
    p.set_defaults(handler=cmd_expert)

    p = commands.add_parser(
        "render", help="draw a layout: head camera and a labelled top view",
        description="Build a scene layout in MuJoCo, let it settle, and save the head camera "
                    "image beside a top view with every body's name.")
    p.add_argument("--scene", required=True, help="scene id, e.g. scene1")
    p.add_argument("--layout", help="layout name (default: the scene's first layout)")
    p.add_argument("-o", "--output", required=True, metavar="OUT.png", help="image file")
    p.add_argument("--seed", type=int, help="apply this episode seed's jitter "
                                            "(default: nominal positions)")
    p.add_argument("--specs", help="spec file or folder (default: " + _SPECS_DEFAULT + ")")
    p.add_argument("--image-size", type=_size, default=(640, 480), metavar="WxH",
                   help="size of each of the two views (default: 640x480)")
    p.set_defaults(handler=cmd_render)
    p = commands.add_parser(
        "eval", help="evaluate a policy over L0-L3: the paper's Table 1",
        description="Run a policy on the compiled episodes (fixed action budget, chunks of at "
                    "most 50 actions, the tasks' seeds), score every episode with the oracle, "
                    "append the results to RUN/episodes.jsonl and write RUN/summary.json; "
                    "prints IS / ES / CR per scene and level. Interrupted runs continue with "
                    "--resume.",
        epilog="examples:\n  robofollow eval --policy expert --out runs/expert\n  robofollow "
               "eval --policy expert --out runs/quick --sample 2 --rounds 1\n  robofollow "
               "eval --policy blind --out runs/blind --levels L0,L1 --rounds 2\n  robofollow "
               "eval --policy mypkg.policies:make --out runs/mine\n\n"
               "A policy failure (an exception or SystemExit in the policy, invalid actions, a "
               "call past\n--policy-timeout, a module:factory policy's process dying, a "
               "server lost) ends its episode,\nwhich is scored as it stands and recorded "
               "with the reason; the run goes on. A policy that\ncannot be built stops the "
               "run before any episode.\n\nexit status: 0 the run finished; 3 it finished "
               "and some episodes ended in a policy failure\n(counted in the summary); 1 an "
               "error stopped it (finished episodes are kept: --resume);\n130 interrupted.",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--policy", required=True,
                   help="expert, blind, noop, random, baseline:NAME (a shipped baseline), a "
                        "checkpoint folder, module:factory, ws://HOST:PORT (openpi) or "
                        "tcp://HOST:PORT (upstream); servers take ?timeout=S&retries=N")
    p.add_argument("--out", required=True, metavar="RUN", help="run folder")
    p.add_argument("--specs", help="spec file or folder (default: " + _SPECS_DEFAULT + ")")
    p.add_argument("--scenes", metavar="LIST", help="comma-separated scenes (default: all)")
    p.add_argument("--levels", metavar="LIST", help="comma-separated levels (default: all)")
    p.add_argument("--tasks", metavar="LIST", help="comma-separated task ids, e.g. "
                   "scene2/L0/pickup_left_cube (default: every task of the scenes and levels)")
    p.add_argument("--sample", type=_positive, metavar="N",
                   help="only N tasks of each scene and level, evenly spread over its task "
                        "list (a quick look; default: every task)")
    p.add_argument("--rounds", type=_positive, default=10, metavar="N",
                   help="rounds per task, each with its own seed (default: 10)")
    p.add_argument("--workers", type=_positive, default=os.cpu_count() or 1, metavar="N",
                   help="workers, one simulation each (default: the number of CPUs)")
    p.add_argument("--executor", choices=EXECUTORS, default="process",
                   help="process: a local process pool; ray: Ray actors on the cluster at "
                        "RAY_ADDRESS, or a local one (needs robofollow[ray]); the results are "
                        "the same (default: process)")
    p.add_argument("--instruction-mode", choices=("normal", "empty", "shuffled"),
                   default="normal", help="the episode's instruction, none, or another "
                                          "task's (default: normal)")
    p.add_argument("--video", choices=("none", "failures", "all"), default="none",
                   help="write mp4s of these episodes to RUN/videos (default: none)")
    p.add_argument("--policy-timeout", type=_seconds, metavar="S",
                   help="end an episode whose in-process policy takes longer than S seconds "
                        "over a reset() or act() call, recording it as a policy failure "
                        "(default: 60; servers take ?timeout=S&retries=N, default 60)")
    p.add_argument("--allow-privileged", action="store_true",
                   help="let a policy server (ws:// or tcp://) that asks for them have "
                        "privileged observations: each episode's scene, layout and seed, from "
                        "which it can rebuild the simulation's ground truth. Without it such a "
                        "server is refused. Recorded in the run as ?privileged=1 on --policy; "
                        "servers also take ?max_message=BYTES (largest reply, default 16 MiB)")
    p.add_argument("--resume", action="store_true", help="continue an interrupted run")
    p.add_argument("--drop-corrupt", action="store_true",
                   help="with --resume: move corrupt lines of RUN/episodes.jsonl (which stop a "
                        "resume, with their line numbers) to RUN/episodes.jsonl.dropped and "
                        "evaluate their episodes again")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(handler=cmd_eval)

    p = commands.add_parser(
        "report", help="rebuild a run's report, or compare two runs",
        description="With one RUN: rebuild RUN/report.md and RUN/report.html from its results. "
                    "With two: their Table 1 cells side by side with the differences "
                    "(markdown, printed or written to --out).")
    p.add_argument("runs", nargs="+", metavar="RUN", help="one or two run folders")
    p.add_argument("--out", metavar="FILE.md", help="write the comparison here")
    p.set_defaults(handler=cmd_report)

    p = commands.add_parser(
        "serve", help="serve a Python policy over openpi's websocket or upstream's TCP protocol",
        description="Expose a policy (a reference policy or module:factory) as a server: "
                    "websocket speaking openpi's protocol (msgpack-numpy, metadata on connect, "
                    "replies {'actions': [H, 14]}), for `robofollow eval --policy ws://HOST:PORT`"
                    " or any openpi client; or tcp speaking upstream RoboFollow's protocol "
                    "(length-prefixed JSON; reset / set_instruction / predict), for "
                    "`robofollow eval --policy tcp://HOST:PORT` or upstream's evaluator.")
    p.add_argument("--protocol", choices=("websocket", "tcp"), default="websocket",
                   help="wire protocol (default: websocket)")
    p.add_argument("--policy", required=True, help="expert, blind, noop, random, "
                   "baseline:NAME, a checkpoint folder, or module:factory")
    p.add_argument("--host", default="127.0.0.1",
                   help="address to listen on (default: 127.0.0.1, this machine only; "
                        "--host 0.0.0.0 exposes the server to every network this machine is "
                        "on, without authentication: only on a network you trust)")
    p.add_argument("--port", type=_positive, default=8000, help="port (default: 8000)")
    p.add_argument("--max-message", type=_positive, metavar="BYTES",
                   help="refuse requests larger than this, closing the connection (default: "
                        "16777216, 16 MiB; three 320x240 images take about 1 MiB)")
    p.add_argument("--idle-timeout", type=_seconds, metavar="S",
                   help="close a connection that sends nothing for S seconds (default: 300)")
    p.add_argument("--max-clients", type=_positive, metavar="N",
                   help="connections served at once, each with its own instance of the "
                        "policy; more are refused (default: 8)")
    p.add_argument("--specs", help="spec file or folder (default: " + _SPECS_DEFAULT + ")")
    p.set_defaults(handler=cmd_serve)

    p = commands.add_parser(
        "generate", help="record expert demonstrations of the training tasks as a dataset",
        description="Run the scripted expert on every training task (seeds fixed per task and "
                    "episode; an attempt the oracle does not score complete is discarded and "
                    "the next seed tried) and write a LeRobot v2.1 / v3.0 or HDF5 dataset with "
                    "the 14-D state and action, three camera videos and the instruction. "
                    "Interrupted runs continue with --resume.",
        epilog="examples:\n  robofollow generate specs/ --out demos/            # 50 per "
               "task, 3,750 episodes\n  robofollow generate specs/ --out small/ "
               "--tasks scene1,pickup_left_cube --episodes-per-task 3\n  robofollow dataset "
               "check demos/", formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("specs", nargs="?", help="a spec file or a folder of .rf files "
                                            "(default: " + _SPECS_DEFAULT + ")")
    p.add_argument("--out", required=True, metavar="DIR", help="dataset folder (new or empty, "
                                                              "or the one to --resume)")
    p.add_argument("--episodes-per-task", type=_positive, default=50, metavar="N",
                   help="demonstrations per training task (default: 50)")
    p.add_argument("--tasks", metavar="LIST", help="comma-separated training task labels "
                   "and/or scene ids (default: every training task)")
    p.add_argument("--workers", type=_positive, default=os.cpu_count() or 1, metavar="N",
                   help="worker processes, one renderer each (default: the number of CPUs)")
    p.add_argument("--format", choices=FORMATS,
                   default="lerobot-v2.1", help="dataset format (default: lerobot-v2.1)")
    p.add_argument("--image-size", type=_size, default=(320, 240), metavar="WxH",
                   help="camera image size (default: 320x240)")
    p.add_argument("--instructions", choices=INSTRUCTION_MODES, default="sample",
                   help="sample: one paraphrase per episode; all: every paraphrase as its own "
                        "episode (default: sample)")
    p.add_argument("--resume", action="store_true",
                   help="continue an interrupted run in DIR (same options)")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p.set_defaults(handler=cmd_generate)

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
    p.add_argument("--specs", help="spec file or folder (default: " + _SPECS_DEFAULT + ")")
    p.add_argument("--scene", default="scene2", help="scene id (default: scene2)")
    p.add_argument("--layout", help="layout name (default: the scene's first layout)")
    p.add_argument("--out", metavar="DIR", help="new folder for images and questions")
    p.add_argument("--count", type=_positive, default=20, metavar="N",
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

    p = commands.add_parser(
        "train", help="train a learned baseline on a dataset (CPU; needs robofollow[train])",
        description="Behaviour cloning from scratch (no downloaded weights) on a LeRobot v2.1 / "
                    "v3.0 dataset written by `robofollow generate`: a small CNN over the "
                    "cameras, the joint state and the instruction (text: its words; form: its "
                    "logical form; blind: nothing) predict chunks of joint targets (L1 loss). "
                    "Checkpoints go to OUT every --checkpoint-every steps and at the end; an "
                    "interrupted run continues with --resume. CKPT is then a policy: "
                    "`robofollow eval --policy CKPT`.",
        epilog="examples:\n  robofollow generate --out demos/scene2 --tasks scene2\n  "
               "robofollow train demos/scene2 --policy text --out runs/scene2-text\n  "
               "robofollow train demos/scene2 --policy text --out runs/scene2-text --resume\n"
               "  robofollow eval --policy runs/scene2-text --out runs/eval-text "
               "--scenes scene2", formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("dataset", metavar="DATASET", help="dataset folder")
    p.add_argument("--policy", choices=("text", "blind", "form"),
                   help="what the network reads of the instruction (default: text)")
    p.add_argument("--out", required=True, metavar="CKPT", help="checkpoint folder (new, "
                                                               "or the one to --resume)")
    p.add_argument("--steps", type=_positive, help="training steps (default: 10000)")
    p.add_argument("--batch", type=_positive, help="samples per step (default: 64)")
    p.add_argument("--learning-rate", type=float, metavar="LR",
                   help="Adam's peak learning rate (default: 0.001)")
    p.add_argument("--seed", type=int, help="initialisation, order, augmentation and "
                                            "held-out split (default: 0)")
    p.add_argument("--cameras", type=_cameras, metavar="LIST",
                   help="comma-separated cameras (default: cam_high)")
    p.add_argument("--factor", type=_positive, help="shrink camera images by this factor "
                                                    "(default: 4: 320x240 -> 80x60)")
    p.add_argument("--shift", type=int, metavar="PX",
                   help="random-shift augmentation in pixels (default: 4)")
    p.add_argument("--chunk", type=_positive, help="actions predicted per query (default: 50)")
    p.add_argument("--execute", type=_positive,
                   help="actions of each chunk executed before the next query (default: 25)")
    p.add_argument("--val-fraction", type=float, metavar="F",
                   help="held-out demonstrations per task for the validation loss "
                        "(default: 0.05)")
    p.add_argument("--checkpoint-every", type=_positive, metavar="N",
                   help="steps between checkpoints (default: 1000)")
    p.add_argument("--episodes-per-task", type=_positive, metavar="N",
                   help="train on the first N demonstrations of each task (default: all)")
    p.add_argument("--variants-per-task", type=_positive, metavar="N",
                   help="train only on episodes worded with one of each task's first N "
                        "instructions (default: all)")
    p.add_argument("--resume", action="store_true",
                   help="continue the run in CKPT with its recorded options")
    p.add_argument("--stop-at", type=_positive, metavar="STEP",
                   help="stop (with a checkpoint) at this step; --resume goes on from there "
                        "(splits a long run into sittings; the result is the same)")
    p.add_argument("--no-cache", action="store_true",
                   help="decode the videos without reading or writing the frame cache "
                        "(~/.cache/robofollow/frames)")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p.set_defaults(handler=cmd_train)

    p = commands.add_parser("dataset", help="dataset tools (check)",
                            description="Tools for generated datasets.")
    tools = p.add_subparsers(dest="tool", metavar="TOOL", required=True)
    q = tools.add_parser(
        "check", help="validate a dataset against its format's rules",
        description="Validate a LeRobot v2.1 / v3.0 or HDF5 dataset: features, shapes, dtypes, "
                    "fps, indices, timestamps, frame counts against the videos, statistics. "
                    "Prints the findings; exit status 1 when there is any.")
    q.add_argument("dataset", metavar="DIR", help="the dataset folder")
    q.add_argument("--json", action="store_true", help="print the report as JSON")
    q.set_defaults(handler=cmd_dataset_check)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.handler(args)
    except RoboFollowError as error:
        text = error.render()
        if type(error).render is RoboFollowError.render:  # a plain message: say what it is
            text = f"error: {text}"
        print(text, file=sys.stderr)
        return 1
    except BrokenPipeError:  # output piped into e.g. `head`, which stopped reading
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115  (no flush error at exit)
        return 1


if __name__ == "__main__":
    sys.exit(main())
