"""Reports of an evaluation run (`RUN/report.md`, `RUN/report.html`) and comparisons of two:
the paper's Table 1 (with an Intent heatmap in HTML), Intent minus Execution per cell, a
per-task table, what the policy did instead (per cell, the most frequent confusions and, in
HTML, the instructed x executed matrix per scene), the stages that failed first with their
most common reasons, and links to failure videos."""

from __future__ import annotations

import json
import re
from collections import Counter, defaultdict
from pathlib import Path

import jinja2
import numpy as np

from robofollow.compiler.spec import LEVELS
from robofollow.errors import RoboFollowError
from robofollow.eval.run_folder import RESULTS, RUN_FILE, read_results
from robofollow.eval.runner import EvalOptions, summary
from robofollow.oracle.metrics import METRICS, table

# Every HTML template (`*.html.j2`) escapes what it shows: run records hold text from
# policies and policy servers (error messages), which must never become markup. No template
# marks a value |safe.
_TEMPLATES = jinja2.Environment(
    loader=jinja2.PackageLoader("robofollow.eval", "templates"),
    autoescape=jinja2.select_autoescape(["html", "html.j2"], default_for_string=True,
                                        default=False),
    trim_blocks=True, lstrip_blocks=True, undefined=jinja2.StrictUndefined)
VIDEO_LINK = re.compile(r"videos/[A-Za-z0-9_.#-]+\.mp4")  # what the runner writes
DID = ("as instructed", "another training behaviour", "the other branch", "unrecognised")
TOP = 15  # confusions and failure reasons listed


class ReportError(RoboFollowError):
    """A folder that holds no evaluation run."""


def load_run(run: Path) -> tuple[EvalOptions, list[dict]]:
    if not (run / RUN_FILE).is_file():
        raise ReportError(f"{run} holds no evaluation run (no {RUN_FILE})")
    data = json.loads((run / RUN_FILE).read_text(encoding="utf-8"))
    options = EvalOptions(**dict(data, scenes=tuple(data["scenes"]),
                                 levels=tuple(data["levels"]), tasks=tuple(data["tasks"])))
    return options, read_results(run / RESULTS)


def _short(task: str) -> str:
    return task.rsplit("/", 1)[-1]


def _did(record: dict) -> str:
    match = (record["executed_behaviour"] or {}).get("match")
    if match == "instructed":
        return DID[0]
    if match == "other branch":
        return DID[2]
    return DID[1] if match else DID[3]


def report_data(name: str, options: EvalOptions, results: list[dict]) -> dict:
    """Everything the templates show, computed once."""
    totals = summary(results, options)
    cells = totals["cells"]
    levels = [level for level in LEVELS if any(level in row for row in cells.values())]
    tasks = []
    for task, records in sorted(_group(results, "task").items()):
        done = [r["complete"] for r in records]
        tasks.append({"task": task, "episodes": len(records),
                      "IS": 100 * np.mean([r["intent_score"] for r in records]),
                      "ES": 100 * np.mean([r["execution_score"] for r in records]),
                      "CR": 100 * np.mean(done)})
    did = {}
    for (scene, level), records in sorted(_group(results, "scene", "level").items()):
        counts = Counter(_did(r) for r in records)
        did.setdefault(scene, {})[level] = {k: 100 * counts[k] / len(records) for k in DID}
    confusions = Counter((_short(r["task"]), r["executed_behaviour"]["match"])
                         for r in results if _did(r) == DID[1])
    matrices = {}
    for scene, records in sorted(_group(results, "scene").items()):
        counts = Counter((_short(r["task"]), (r["executed_behaviour"] or {}).get("match")
                          or "none") for r in records)
        rows = sorted({row for row, _ in counts})
        columns = sorted({column for _, column in counts}, key=lambda c: (c != "instructed", c))
        matrices[scene] = {"rows": rows, "columns": columns,
                           "counts": {f"{r}|{c}": n for (r, c), n in counts.items()}}
    failures = Counter()
    reasons: dict[str, Counter] = defaultdict(Counter)
    for record in results:
        failed = next((s for s in record["stages"] if s["intent"] < s["weight"]
                       or s["execution"] < s["weight"]), None)
        if failed is not None:
            failures[failed["stage"]] += 1
            reasons[failed["stage"]][failed["reason"]] += 1
    return {
        "name": name, "options": options, "summary": totals, "levels": levels,
        "metrics": METRICS, "cells": cells, "tasks": tasks, "did": did, "did_kinds": DID,
        "confusions": confusions.most_common(TOP), "matrices": matrices,
        "first_failures": [{"stage": stage, "episodes": count,
                            "reasons": reasons[stage].most_common(3)}
                           for stage, count in failures.most_common()],
        "errors": Counter(r["error"].split(": ", 1)[-1] for r in results if r["error"]
                          ).most_common(TOP),
        "clipped": {"actions": sum(r.get("clipped", 0) for r in results),
                    "episodes": sum(1 for r in results if r.get("clipped"))},
        "videos": [(r["episode"], r["video"]) for r in results
                   if isinstance(r.get("video"), str) and VIDEO_LINK.fullmatch(r["video"])][:50]}


def _group(results: list[dict], *keys: str) -> dict:
    grouped: dict = defaultdict(list)
    for record in results:
        grouped[record[keys[0]] if len(keys) == 1 else tuple(record[k] for k in keys)].append(
            record)
    return grouped


def write_report(run: Path) -> tuple[Path, Path]:
    """(Re)build RUN/report.md and RUN/report.html from the run's results."""
    options, results = load_run(run)
    data = report_data(run.name, options, results)
    paths = run / "report.md", run / "report.html"
    for path in paths:
        template = _TEMPLATES.get_template(f"report{path.suffix}.j2")
        path.write_text(template.render(**data), encoding="utf-8")
    return paths


def comparison(runs: list[Path]) -> str:
    """Markdown: the runs' Table 1 cells side by side, with B - A differences."""
    loaded = [load_run(run) for run in runs]
    tables = [table(results) for _, results in loaded]
    template = _TEMPLATES.get_template("compare.md.j2")
    return template.render(runs=[run.name for run in runs], options=[o for o, _ in loaded],
                           tables=tables, metrics=METRICS, levels=LEVELS)
