"""Table 1 of a run for a paper: RUN/table1.csv (one row per scene and level, every metric with
its 95% interval over tasks, chance and n) or RUN/table1.tex (a booktabs table, each cell
"IS [low, high]" in the paper's layout: scenes as rows, L0-L3 as column groups). A cell of one
task has no interval over tasks: its bounds are blank (the reports say "n/a")."""

from __future__ import annotations

import csv
import io

from robofollow.compiler.scene.spec import LEVELS
from robofollow.eval.statistics.metrics import METRICS


def table1_csv(summary: dict) -> str:
    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow(["scene", "level", "tasks", "episodes",
                     *[f"{m}{part}" for m in METRICS for part in ("", "_low", "_high")],
                     "chance_IS", "chance_CR"])
    for scene, row in summary["cells"].items():
        for level in LEVELS:
            if level not in row:
                continue
            cell = row[level]
            writer.writerow([scene, level, cell["tasks"], cell["episodes"],
                             *[text for m in METRICS
                               for text in (f"{cell[m]:.1f}", *_bounds(cell["ci95_tasks"][m]))],
                             _optional(cell.get("chance_IS")), _optional(cell.get("chance_CR"))])
    avg = summary["avg"]
    writer.writerow(["avg", "", "", summary.get("episodes", ""),
                     *[v for m in METRICS for v in (f"{avg[m]:.1f}", "", "")],
                     _optional(summary.get("references", {}).get("chance_IS")),
                     _optional(summary.get("references", {}).get("chance_CR"))])
    return text.getvalue()


def _optional(value: float | None) -> str:
    return "" if value is None else f"{value:.1f}"


def _bounds(interval: list[float] | None) -> tuple[str, str]:
    return ("", "") if interval is None else tuple(f"{b:.1f}" for b in interval)


LATEX_SPECIAL = {char: "\\" + char for char in "&%$#_{}"} | {
    "~": r"\textasciitilde{}", "^": r"\textasciicircum{}", "\\": r"\textbackslash{}"}


def latex_text(text: str) -> str:
    """Text as LaTeX prints it (its special characters escaped)."""
    return "".join(LATEX_SPECIAL.get(char, char) for char in text)


def table1_latex(summary: dict, caption: str) -> str:
    """Scenes as rows; per level, IS / ES / CR each with its interval over tasks in small
    type beneath (\\makecell needs the makecell package, \\toprule booktabs); `caption` is
    plain text."""
    cells = summary["cells"]
    levels = [level for level in LEVELS if any(level in row for row in cells.values())]
    spec = "l" + "ccc" * len(levels)
    lines = [r"\begin{table}[t]", r"\centering", r"\small",
             rf"\begin{{tabular}}{{{spec}}}", r"\toprule",
             " & " + " & ".join(rf"\multicolumn{{3}}{{c}}{{{level}}}" for level in levels)
             + r" \\",
             " ".join(rf"\cmidrule(lr){{{2 + 3 * i}-{4 + 3 * i}}}" for i in range(len(levels))),
             "Scene & " + " & ".join(" & ".join(METRICS) for _ in levels) + r" \\",
             r"\midrule"]
    for scene, row in cells.items():
        values = []
        for level in levels:
            cell = row.get(level)
            for metric in METRICS:
                if cell is None:
                    values.append("--")
                    continue
                bounds = cell["ci95_tasks"][metric]
                values.append(f"{cell[metric]:.1f}" if bounds is None else
                              rf"\makecell{{{cell[metric]:.1f}\\ \tiny[{bounds[0]:.1f}, "
                              rf"{bounds[1]:.1f}]}}")
        lines.append(latex_text(scene) + " & " + " & ".join(values) + r" \\")
    avg = summary["avg"]
    lines += [r"\midrule",
              (rf"Avg & \multicolumn{{{3 * len(levels)}}}{{l}}{{IS {avg['IS']:.1f}, "
               rf"ES {avg['ES']:.1f}, CR {avg['CR']:.1f}}} \\"),
              r"\bottomrule", r"\end{tabular}",
              rf"\caption{{{latex_text(caption)}}}", r"\end{table}", ""]
    return "\n".join(lines)
