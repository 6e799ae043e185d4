"""A comparison of runs as pages: markdown, HTML with a forest plot per metric, and the JSON,
written to the folder chosen for it (docs/statistics.md)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from robofollow.errors import UsageError
from robofollow.eval.reports.pages import PAGES, p_value, signed, signed_interval
from robofollow.eval.running.run_folder import (
    check_folder_out,
    safe_path,
    write_text_file,
)
from robofollow.eval.statistics.metrics import METRICS
from robofollow.eval.statistics.paired import ALPHA

_PLOT = {"width": 520, "row": 22, "label": 170, "top": 28}  # a forest plot's geometry (px)


def forest(result: dict, metric: str) -> dict:
    """A forest plot of a metric's differences: each row's estimate and interval in pixels,
    the zero line, and ticks (the SVG in compare.html.j2 draws it)."""
    rows = result["rows"]
    values = [0.0] + [v for r in rows for v in [r[metric]["difference"],
                                                *(r[metric]["interval"] or [])]]
    low, high = min(values), max(values)
    pad = max((high - low) * 0.05, 1.0)
    low, high = low - pad, high + pad
    step = next(s for s in (1, 2, 5, 10, 20, 25, 50) if (high - low) / s <= 10)

    def x(value: float) -> float:
        return round(_PLOT["label"] + (value - low) / (high - low) * _PLOT["width"], 1)

    drawn = []
    for index, row in enumerate(rows):
        cell = row[metric]
        bounds = cell["interval"] or [cell["difference"], cell["difference"]]
        name = f"{row['scene']} {row['level']}".replace("all avg", "average")
        drawn.append({"label": f"{name} · {row['tasks']} tasks",
                      "y": _PLOT["top"] + index * _PLOT["row"], "x": x(cell["difference"]),
                      "low": x(bounds[0]), "high": x(bounds[1]),
                      "told_apart": cell["p_holm"] < ALPHA,
                      "title": f"{cell['difference']:+.1f} {signed_interval(cell['interval'])}, "
                               f"p (Holm) {p_value(cell['p_holm'])}, {row['tasks']} tasks, "
                               f"{row['episodes']} pairs"})
    first = step * np.ceil(low / step)
    ticks = [{"x": x(v), "label": f"{v:+g}" if v else "0"} for v in np.arange(first, high, step)]
    return {"rows": drawn, "zero": x(0.0), "ticks": ticks, "metric": metric,
            "height": _PLOT["top"] + len(rows) * _PLOT["row"] + 24,
            "width": _PLOT["label"] + _PLOT["width"] + 20}


def html(result: dict) -> str:
    """The comparison as a page: verdicts, a forest plot and a table per metric."""
    return PAGES.get_template("compare.html.j2").render(
        result=result, a=Path(result["a"]).name, b=Path(result["b"]).name, metrics=METRICS,
        plots={metric: forest(result, metric) for metric in METRICS})


def markdown(result: dict) -> str:
    """The comparison as markdown: verdicts, then a table per metric."""
    a, b = Path(result["a"]).name, Path(result["b"]).name
    pairing = result["pairing"]
    lines = [f"# {a} − {b}", "",
             (f"{pairing['pairs']} paired episodes (by id, the same episode hash and, where "
              "recorded, the same start); "
              f"differences are {a} − {b} in points, with 95% intervals over tasks (a cluster "
              "bootstrap) and sign-flip p-values over tasks, adjusted by Holm's method over "
              "every row of a metric (docs/statistics.md)."), ""]
    lines += [f"- {warning}" for warning in result["warnings"]]
    lines += ["", "## Verdicts (Intent)", ""] + [f"- {v}" for v in result["verdicts"]]
    for metric in METRICS:
        lines += ["", f"## {metric}", "",
                  f"| Scene | Level | {a} | {b} | Δ | 95% interval | p | p (Holm) | n |",
                  "|---|---|---:|---:|---:|---|---:|---:|---|"]
        for row in result["rows"]:
            cell = row[metric]
            n = f"{row['tasks']} tasks, {row['episodes']} pairs"
            lines.append(f"| {row['scene']} | {row['level']} | {cell['A']:.1f} | "
                         f"{cell['B']:.1f} | {signed(cell['difference'])} | "
                         f"{signed_interval(cell['interval'])} | {p_value(cell['p'])} | "
                         f"{p_value(cell['p_holm'])} | {n} |")
    return "\n".join(lines) + "\n"


def comparison_folders(a: Path, others: list[Path], out: Path) -> list[Path]:
    """Where each comparison of `others` with `a` is written: `out` for one; else
    out/<A>-vs-<B>, each B named by as many of its last path parts as tell the runs apart,
    joined by "-"; where two names still read alike (p/a/b-c and p/a-b/c), the later ones get
    -2, -3 (each compare.json names its runs). Two comparisons never share a folder."""
    if len(others) == 1:
        return [out]
    paths = [other.resolve() for other in others]
    if len(set(paths)) < len(paths):
        raise UsageError("a run is given twice; each run is compared with the first once")
    depth = next(d for d in range(1, max(len(p.parts) for p in paths) + 1)
                 if len({p.parts[-d:] for p in paths}) == len(paths))
    names: list[str] = []
    for path in paths:
        name = unique = "-".join(path.parts[-depth:])
        count = 1
        while unique in names:
            count += 1
            unique = f"{name}-{count}"
        names.append(unique)
    return [out / f"{a.name}-vs-{name}" for name in names]


def write_comparison_files(result: dict, out: Path) -> None:
    """OUT/compare.md, compare.html and compare.json of one comparison."""
    check_folder_out(out)
    for name, text in (("compare.md", markdown(result)), ("compare.html", html(result)),
                       ("compare.json", json.dumps(result, indent=2) + "\n")):
        write_text_file(safe_path(out, name), text)
