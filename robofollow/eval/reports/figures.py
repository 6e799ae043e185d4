"""The figures of reports, drawn with matplotlib (the `figures` extra) into FOLDER/figures/:
an SVG the HTML shows and a PDF beside it for papers, both byte-identical for the same data.

A run's report: IS / ES / CR per level and scene with their intervals over tasks and chance;
the drop from L0 per scene; Intent minus chance as a diverging heatmap; Intent per layout
(L1, L3) and per training task (L2, L3). A comparison: several runs on one axis per cell."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from robofollow.eval.running.run_folder import safe_path
from robofollow.eval.statistics.metrics import shown_interval
from robofollow.files import write_bytes_atomic

FIGURES = "figures"  # the folder beside the report
INSTALL = "pip install 'robofollow[figures]'"
COLOURS = ("#4c72b0", "#dd8452", "#55a868", "#c44e52", "#8172b3", "#937860", "#da8bc3",
           "#8c8c8c")
WHISKERS = "whiskers: 95% interval over tasks (cluster bootstrap)"


class FiguresUnavailable(RuntimeError):
    """matplotlib is not installed."""


def _figure(width: float, height: float):
    try:
        import matplotlib
        from matplotlib.figure import Figure
    except ImportError:
        raise FiguresUnavailable(f"figures need matplotlib: {INSTALL}") from None
    matplotlib.rcParams.update({"svg.hashsalt": "robofollow", "svg.fonttype": "none",
                                "pdf.fonttype": 42, "font.size": 8, "axes.titlesize": 9,
                                "axes.spines.top": False, "axes.spines.right": False})
    return Figure(figsize=(width, height), layout="constrained")


def _save(figure, folder: Path, name: str, caption: str) -> dict:
    """The figure as SVG and PDF, each drawn in memory and written whole (write_bytes_atomic):
    a kill mid-write leaves the previous file, never an empty or cut one."""
    out = safe_path(folder, FIGURES)
    out.mkdir(parents=True, exist_ok=True)
    for suffix, metadata in (("svg", {"Date": None}), ("pdf", {"CreationDate": None})):
        drawn = io.BytesIO()
        figure.savefig(drawn, format=suffix, metadata=metadata)
        write_bytes_atomic(safe_path(folder, FIGURES, f"{name}.{suffix}"), drawn.getvalue())
    return {"name": name, "svg": f"{FIGURES}/{name}.svg", "pdf": f"{FIGURES}/{name}.pdf",
            "caption": caption}


def _errors(values: list[float], intervals: list[list[float] | None]) -> np.ndarray:
    """Whisker lengths below and above each value (none where it has no interval)."""
    return np.array([[v - i[0], i[1] - v] if i else [0.0, 0.0]
                     for v, i in zip(values, intervals, strict=True)]).T.clip(min=0)


def run_figures(data: dict, folder: Path) -> list[dict]:
    """Every figure of a run's report (report_data.report_data), written under folder; none
    for a run without episodes."""
    if not data["table"]:
        return []
    made = [_levels(data, folder)]
    if data["drops"]:
        made.append(_drops(data, folder))
    if all(cell.get("chance_IS") is not None for cell in data["table"]):
        made.append(_chance(data, folder))
    for rows, name, what in ((data["layouts"], "layouts", "layout (L1, L3)"),
                             (data["training"], "training", "training task (L2, L3)")):
        if rows:
            made.append(_breakdown(rows, folder, name, what))
    return made


def _levels(data: dict, folder: Path) -> dict:
    cells, levels = data["cells"], data["levels"]
    scenes = list(cells)
    figure = _figure(7.2, 2.4)
    axes = figure.subplots(1, len(data["metrics"]), sharey=True)
    width = 0.8 / len(scenes)
    for ax, metric in zip(axes, data["metrics"], strict=True):
        for s, scene in enumerate(scenes):
            x = [i - 0.4 + width * (s + 0.5) for i, level in enumerate(levels)
                 if level in cells[scene]]
            shown = [cells[scene][level] for level in levels if level in cells[scene]]
            values = [c[metric] for c in shown]
            ax.bar(x, values, width * 0.9, color=COLOURS[s % len(COLOURS)], label=scene,
                   yerr=_errors(values, [shown_interval(c, metric) for c in shown]),
                   error_kw={"elinewidth": 0.8, "capsize": 1.5})
            chance = f"chance_{metric}"
            if all(chance in c for c in shown):
                ax.hlines([c[chance] for c in shown], [v - width / 2 for v in x],
                          [v + width / 2 for v in x], colors="black", linewidth=1.2)
        ax.set_xticks(range(len(levels)), levels)
        ax.set_title(metric)
        ax.set_ylim(0, 105)
    axes[0].set_ylabel("score (0-100)")
    figure.legend(*axes[0].get_legend_handles_labels(), fontsize=7, frameon=False,
                  loc="outside right upper")  # (beside the panels: inside, it hid bars)
    return _save(figure, folder, "levels",
                 f"IS, ES and CR per level and scene; {WHISKERS}; black ticks: chance (a "
                 "language-blind guess). n per bar: its cell's tasks × rounds (Table 1).")


def _drops(data: dict, folder: Path) -> dict:
    rows = data["drops"]
    figure = _figure(4.8, 0.3 + 0.24 * len(rows))
    ax = figure.subplots()
    y = np.arange(len(rows))[::-1]
    values = [row["IS"]["drop"] for row in rows]
    ax.errorbar(values, y, xerr=_errors(values, [row["IS"]["interval"] for row in rows]),
                fmt="o", color=COLOURS[0], markersize=3, elinewidth=0.8, capsize=2)
    ax.axvline(0, color="grey", linewidth=0.8)
    ax.set_yticks(y, [f"{row['scene']} L0→{row['level']} "
                      f"({'paired' if row['paired'] else 'unpaired'}; "
                      f"n {row['tasks'][0]}, {row['tasks'][1]})" for row in rows])
    ax.set_xlabel("Intent drop from L0 (points)")
    return _save(figure, folder, "drops",
                 f"The drop in Intent from L0 to each later level, per scene; {WHISKERS} "
                 "(L1 paired by training task, L2 and L3 unpaired); n: L0 tasks, level tasks.")


def _chance(data: dict, folder: Path) -> dict:
    scenes, levels = list(data["cells"]), data["levels"]
    grid = np.full((len(scenes), len(levels)), np.nan)
    flagged = {(c["scene"], c["level"]) for c in data["table"] if c["below_chance"]}
    for cell in data["table"]:
        grid[scenes.index(cell["scene"]), levels.index(cell["level"])] = (
            cell["IS"] - cell["chance_IS"])
    figure = _figure(1.6 + 0.9 * len(levels), max(1.8, 0.6 + 0.4 * len(scenes)))
    ax = figure.subplots()
    limit = max(10.0, float(np.nanmax(np.abs(grid))))
    image = ax.imshow(grid, cmap="RdBu", vmin=-limit, vmax=limit, aspect="auto")
    for (i, j), value in np.ndenumerate(grid):
        if not np.isnan(value):
            mark = " ▼" if (scenes[i], levels[j]) in flagged else ""
            ax.text(j, i, f"{value:+.1f}{mark}", ha="center", va="center", fontsize=7,
                    color="white" if abs(value) > 0.6 * limit else "black")
    ax.set_xticks(range(len(levels)), levels)
    ax.set_yticks(range(len(scenes)), scenes)
    figure.colorbar(image, ax=ax, label="IS − chance (points)")
    return _save(figure, folder, "chance",
                 "Intent minus chance Intent per cell (blue above chance, red below); ▼: "
                 "below chance, the cell's 95% interval over tasks entirely under it.")


def _breakdown(rows: list[dict], folder: Path, name: str, what: str) -> dict:
    """One panel per scene: a row per layout or training task, a dot per level, a tick at
    chance."""
    scenes = sorted({r["scene"] for r in rows})
    levels = sorted({r["level"] for r in rows})
    keys = {scene: sorted({r["key"] for r in rows if r["scene"] == scene}) for scene in scenes}
    figure = _figure(6.0, 0.6 + 0.16 * sum(len(k) for k in keys.values()) + 0.3 * len(scenes))
    axes = figure.subplots(len(scenes), 1, sharex=True, squeeze=False,
                           height_ratios=[len(keys[scene]) + 1 for scene in scenes])[:, 0]
    for ax, scene in zip(axes, scenes, strict=True):
        place = {key: len(keys[scene]) - i for i, key in enumerate(keys[scene])}
        for number, level in enumerate(levels):
            found = [r for r in rows if r["scene"] == scene and r["level"] == level]
            ax.plot([r["IS"] for r in found], [place[r["key"]] for r in found], "o",
                    color=COLOURS[number], markersize=3.5, label=level)
            chance = [r for r in found if r["chance_IS"] is not None]
            ax.plot([r["chance_IS"] for r in chance], [place[r["key"]] for r in chance], "|",
                    color="black", markersize=6)
        ax.set_yticks(list(place.values()), list(place), fontsize=6)
        ax.set_ylim(0.3, len(place) + 0.7)
        ax.set_title(scene, loc="left")
        ax.grid(axis="x", color="#eee")
    axes[0].legend(fontsize=7, frameon=False, ncols=len(levels), loc="lower right",
                   bbox_to_anchor=(1, 1))
    axes[-1].set_xlim(-2, 102)
    axes[-1].set_xlabel("Intent (0-100)")
    return _save(figure, folder, name,
                 f"Intent per {what}, one dot per level: the mean over its tasks and rounds "
                 "(their n in the report's table); black ticks: chance.")


def comparison_figure(runs: list[str], summaries: list[dict], folder: Path) -> dict:
    """Several runs' Intent per scene and level on one axis, with intervals over tasks."""
    keys = sorted({(scene, level) for s in summaries for scene, row in s["cells"].items()
                   for level in row}, key=lambda k: (k[1], k[0]))
    figure = _figure(max(6.0, 0.22 * len(keys) * len(runs) + 1.5), 2.8)
    ax = figure.subplots()
    width = 0.8 / len(runs)
    for r, (run, found) in enumerate(zip(runs, summaries, strict=True)):
        present = [(i, found["cells"][s][lv]) for i, (s, lv) in enumerate(keys)
                   if lv in found["cells"].get(s, {})]
        values = [c["IS"] for _, c in present]
        ax.bar([i - 0.4 + width * (r + 0.5) for i, _ in present], values, width * 0.9,
               color=COLOURS[r % len(COLOURS)], label=run,
               yerr=_errors(values, [shown_interval(c, "IS") for _, c in present]),
               error_kw={"elinewidth": 0.8, "capsize": 1.5})
    chance = {key: found["cells"][key[0]][key[1]].get("chance_IS") for found in summaries
              for key in keys if key[1] in found["cells"].get(key[0], {})}
    shown = [(i, chance[key]) for i, key in enumerate(keys) if chance.get(key) is not None]
    if shown:
        ax.hlines([c for _, c in shown], [i - 0.45 for i, _ in shown],
                  [i + 0.45 for i, _ in shown], colors="black", linewidth=1.2)
    ax.set_xticks(range(len(keys)), [f"{lv}\n{s}" for s, lv in keys], fontsize=6)
    ax.set_ylim(0, 105)
    ax.set_ylabel("Intent (0-100)")
    ax.legend(fontsize=7, frameon=False, ncols=min(len(runs), 4), loc="lower right",
              bbox_to_anchor=(1, 1))
    return _save(figure, folder, "runs",
                 f"Intent per scene and level, one bar per run; {WHISKERS}; black ticks: "
                 "chance.")
