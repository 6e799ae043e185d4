"""Reports of an evaluation run and comparisons of several.

A run's report (RUN/report.md, RUN/report.html, RUN/tasks.html, RUN/figures/): findings,
Table 1 with chance and the cells below it, figures, the drop from L0, language effects, L1 and
L3 split by motion, per-layout and per-training-task summaries, what the policy did, where it
failed first, failure videos beside their cell; every task and the instructed x executed
matrices in tasks.html (report_data.py computes it all). Rebuilt from the full records or,
for a run that keeps only those, its score file; never from fewer episodes than its summary
counts.

A comparison of runs: their Table 1 cells side by side on the episodes every run holds (said
when the runs hold different ones), the differences from the first run and the paired
differences with intervals over tasks (comparison.py); as markdown, or a folder with HTML and a
figure of every run on one axis."""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path

from robofollow.compiler.scene.spec import LEVELS
from robofollow.errors import RoboFollowError, named
from robofollow.eval.reports.comparison import (
    CompareError,
    compare_runs,
    control_comparisons,
    test_set_hashes,
)
from robofollow.eval.reports.comparison_page import markdown
from robofollow.eval.reports.figures import (
    FiguresUnavailable,
    comparison_figure,
    run_figures,
)
from robofollow.eval.reports.pages import PAGES
from robofollow.eval.reports.report_data import report_data
from robofollow.eval.running.run_folder import (
    CONTROLS,
    SUMMARY,
    check_folder_out,
    control_arms,
    safe_path,
    summarised_episodes,
    write_text_file,
)
from robofollow.eval.running.runner import EvalOptions, with_motion
from robofollow.eval.running.saved_run import (
    load_options,
    load_provenance,
    load_records,
    load_run,
)
from robofollow.eval.statistics.metrics import METRICS, MOTIONS, table

PAGES_OF_A_RUN = ("report.md", "report.html", "tasks.html")


class ReportError(RoboFollowError):
    """A report that cannot be made as asked."""


def write_report(run: Path, motions: dict[str, str | None] | None = None,
                 controls: list[dict] | None = None) -> tuple[Path, Path]:
    """(Re)build the run's report pages and figures from its records; `motions` (the
    compiled episodes' motion, by episode id) fills in the records written before they carried
    it (else their motion is unknown: "-"); `controls`: the run against its control arms
    where the caller has them (else compared here). Refused, leaving the report as it is,
    where fewer episodes are found than the run's summary counts. Returns the markdown and
    HTML reports."""
    options, results = load_run(run)
    missing = [mode for mode in options.controls if mode not in control_arms(run)]
    if missing:
        print(f"warning: {run}/run.json declares the control arm(s) {', '.join(missing)}, "
              f"which {run / CONTROLS} lacks: the report is made without them",
              file=sys.stderr)
    counted = summarised_episodes(run)
    if counted is not None and len(results) < counted:
        raise ReportError(f"{run}: its summary counts {counted} episodes but only "
                          f"{len(results)} are here; the report was left as it is")
    unfinished = None if counted is not None else (
        f"An unfinished run (no {SUMMARY}): this report covers the {len(results)} episodes "
        "recorded so far; `robofollow eval` with the run's options and --resume finishes it.")
    if unfinished:
        print(f"warning: {run}: {unfinished}", file=sys.stderr)
    data = report_data(run.name, options, with_motion(results, motions or {}),
                       control_comparisons(run) if controls is None else controls,
                       load_provenance(run))
    data["unfinished"] = unfinished
    try:
        data["figures"], data["figures_missing"] = run_figures(data, run), None
    except FiguresUnavailable as error:
        data["figures"], data["figures_missing"] = [], str(error)
        print(f"{run}: no figures ({error})", file=sys.stderr)
    for name in PAGES_OF_A_RUN:
        write_text_file(safe_path(run, name), PAGES.get_template(f"{name}.j2").render(**data))
    return run / "report.md", run / "report.html"


@dataclass
class Comparison:
    """Runs compared on the episodes they all hold."""
    runs: list[str]
    options: list[EvalOptions]
    tables: list[dict]
    warnings: list[str] = field(default_factory=list)
    paired: list[dict] = field(default_factory=list)  # each later run − the first (compare)
    unpaired: list[str] = field(default_factory=list)  # why a paired comparison is missing


def compare_reports(runs: list[Path], motions: list[dict[str, str | None]] | None = None
                    ) -> Comparison:
    """The runs' Table 1 on the episodes every run holds; under each L1 and L3 cell, its
    moved and its as-trained tasks (`motions`, per run, fills in the records written before
    they carried their task's motion); and each later run against the first, paired."""
    loaded = [(load_options(run), load_records(run)) for run in runs]  # (scores suffice)
    motions = motions or [{} for _ in runs]
    held = [{r["episode"] for r in results} for _, results in loaded]
    common = set.intersection(*held)
    hashes, notes = test_set_hashes(runs), []
    if hashes is not None:  # runs of other test sets: only the episodes the same in all
        same = {e for e in common if len({h.get(e) for h in hashes}) == 1 and e in hashes[0]}
        notes.append(f"the runs were made on different test sets: compared on the "
                     f"{len(same)} of the {len(common)} episodes they all hold that are the "
                     "same in every one")
        common = same
    if not common:
        raise ReportError("the runs share no episode: "
                          + ", ".join(f"{run} holds {len(h)}" for run, h in zip(runs, held,
                                                                                 strict=True)))
    warnings = [f"{run} holds {len(h - common)} episode(s) that another run lacks, left out: "
                f"{named(sorted(h - common))}" for run, h in zip(runs, held, strict=True)
                if h - common]
    if warnings:
        warnings.append(f"compared on the {len(common)} episodes every run holds")
    warnings = notes + warnings
    tables = [table(with_motion([r for r in results if r["episode"] in common], found))
              for (_, results), found in zip(loaded, motions, strict=True)]
    found = Comparison([run.name for run in runs], [o for o, _ in loaded], tables, warnings)
    for run in runs[1:]:
        try:
            found.paired.append(compare_runs(run, runs[0]))
        except CompareError as error:
            found.unpaired.append(f"{run.name} − {runs[0].name}: not available ({error})")
    return found


def side_by_side(tables: list[dict]) -> list[dict]:
    """The rows of the side-by-side table: each scene x level cell, then (for L1 and L3) its
    moved and as-trained tasks; each row with every run's cell (None where it has none)."""
    rows = []
    scenes = sorted({scene for found in tables for scene in found["cells"]})
    for scene in scenes:
        for level in LEVELS:
            cells = [found["cells"].get(scene, {}).get(level) for found in tables]
            if not any(cells):
                continue
            rows.append({"scene": scene, "level": level, "label": level, "cells": cells})
            splits = [(cell or {}).get("by_motion") or {} for cell in cells]
            if any(splits):
                rows += [{"scene": scene, "level": level, "label": f"{level} {kind}",
                          "cells": [split.get(kind) for split in splits]} for kind in MOTIONS]
    return rows


def comparison_markdown(found: Comparison) -> str:
    """The side-by-side tables, then each paired comparison."""
    text = PAGES.get_template("compare.md.j2").render(
        runs=found.runs, options=found.options, tables=found.tables, warnings=found.warnings,
        rows=side_by_side(found.tables), metrics=METRICS)
    for result in found.paired:
        body = markdown(result).split("\n", 1)[1].replace("\n## ", "\n### ")
        text += (f"\n## Paired differences: {Path(result['a']).name} − "
                 f"{Path(result['b']).name} (intervals over tasks)\n" + body)
    return text + "".join(f"\nPaired differences {line}.\n" for line in found.unpaired)


def write_comparison(found: Comparison, out: Path) -> list[Path]:
    """OUT/comparison.md, OUT/comparison.html and the figure of every run on one axis."""
    check_folder_out(out)
    try:
        figure, missing = comparison_figure(found.runs, found.tables, out), None
    except FiguresUnavailable as error:
        figure, missing = None, str(error)
    paths = [safe_path(out, "comparison.md"), safe_path(out, "comparison.html")]
    write_text_file(paths[0], comparison_markdown(found))
    write_text_file(paths[1], PAGES.get_template("runs.html.j2").render(
        runs=found.runs, options=found.options, tables=found.tables, warnings=found.warnings,
        rows=side_by_side(found.tables), paired=found.paired, unpaired=found.unpaired,
        figure=figure, figure_missing=missing, metrics=METRICS))
    return paths
