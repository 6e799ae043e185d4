"""Task-clustered intervals and paired comparisons on synthetic runs with known answers
(docs/statistics.md): identical runs differ by nothing; a run one point better in every
episode is told apart at every level; on clustered benchmarks the interval over tasks covers
the true value about 95% of the time where the Wilson interval over episodes does not."""

from __future__ import annotations

import json

import numpy as np
import pytest

from robofollow.cli import main
from robofollow.eval.reports.comparison import compare_runs, run_scores
from robofollow.eval.reports.comparison_page import markdown
from robofollow.eval.running.scores import write_scores
from robofollow.eval.statistics.intervals import holm, paired_test
from robofollow.eval.statistics.metrics import task_intervals, wilson
from robofollow.eval.statistics.paired import pair

SCENES, LEVELS, TASKS, ROUNDS = ("scene1", "scene2"), ("L0", "L1", "L2", "L3"), 10, 3


def _records(seed: int, shift: float = 0.0) -> list[dict]:
    """A synthetic run: per-task abilities, rounds around them; `shift` added to every
    episode's Intent and Execution."""
    rng = np.random.default_rng(seed)
    records = []
    for scene in SCENES:
        for level in LEVELS:
            for task in range(TASKS):
                ability = rng.uniform(0.1, 0.8)
                for round_index in range(1, ROUNDS + 1):
                    score = float(np.clip(ability + rng.normal(0, 0.1), 0, 0.98))
                    task_id = f"{scene}/{level}/t{task}"
                    records.append({
                        "episode": f"{task_id}#r{round_index}", "scene": scene, "level": level,
                        "task": task_id, "hashes": {"episode": f"h{task}{round_index}"},
                        "intent_score": min(score + shift, 1.0),
                        "execution_score": score / 2 + shift,
                        "complete": bool(score > 0.5)})
    return records


def _run(tmp_path, name: str, records: list[dict]):
    folder = tmp_path / name
    folder.mkdir()
    write_scores(folder / "scores.csv.gz", records)
    return folder


def test_identical_runs_differ_by_nothing(tmp_path):
    result = compare_runs(_run(tmp_path, "a", _records(1)), _run(tmp_path, "b", _records(1)))
    assert result["pairing"]["pairs"] == len(SCENES) * len(LEVELS) * TASKS * ROUNDS
    for row in result["rows"]:
        for metric in ("IS", "ES", "CR"):
            cell = row[metric]
            assert cell["difference"] == 0 and cell["p"] == 1 and cell["p_holm"] == 1
            assert cell["interval"][0] <= 0 <= cell["interval"][1]
    assert all("not told apart" in line for line in result["verdicts"])


def test_one_point_better_everywhere_is_told_apart_at_every_level(tmp_path):
    a = _run(tmp_path, "better", _records(2, shift=0.01))
    result = compare_runs(a, _run(tmp_path, "base", _records(2)))
    levels = {row["level"] for row in result["rows"]}
    assert levels == {*LEVELS, "avg"}
    for row in result["rows"]:
        for metric in ("IS", "ES"):
            cell = row[metric]
            assert cell["difference"] == pytest.approx(1.0)
            assert cell["p_holm"] < 0.05 and cell["interval"][0] > 0, (row["scene"],
                                                                        row["level"], metric)
    assert len(result["verdicts"]) == len(LEVELS) + 1
    assert all(line.startswith("better > base") for line in result["verdicts"])
    assert "| all | L2 |" in markdown(result)


def test_the_interval_over_tasks_covers_where_wilson_does_not():
    """500 simulated cells of 16 tasks x 10 rounds whose tasks differ (success rates drawn
    uniformly): the true mean is 50."""
    rng = np.random.default_rng(7)
    covered = {"tasks": 0, "wilson": 0}
    simulations = 500
    for _ in range(simulations):
        rates = rng.uniform(0, 1, 16)
        episodes = [{"task": f"t{t}", "intent_score": float(rng.random() < rates[t]),
                     "execution_score": 0.0, "complete": False}
                    for t in range(16) for _ in range(10)]
        low, high = task_intervals(episodes)["IS"]
        covered["tasks"] += low <= 50 <= high
        mean = np.mean([e["intent_score"] for e in episodes])
        low, high = wilson(mean, len(episodes))
        covered["wilson"] += low <= 50 <= high
    assert 0.90 <= covered["tasks"] / simulations <= 0.98, covered
    assert covered["wilson"] / simulations < 0.8, covered


def test_pairing_leaves_out_what_does_not_pair_and_names_it(tmp_path):
    a, b = _records(3), _records(3)
    b[0]["hashes"] = {"episode": "another state"}
    del b[1]
    extra = dict(b[2], episode="scene1/L0/t9#r9")
    a[2]["start"], b[1]["start"] = "one start", "another start"  # b[1]: a[2]'s episode
    a[3]["start"] = "a start b does not record"
    pairing = pair(*[[{"episode": r["episode"], "hash": r["hashes"]["episode"],
                       "start": r.get("start", "")} for r in run] for run in (a, b + [extra])])
    assert pairing.other_episode == [a[0]["episode"]]
    assert pairing.other_start == [a[2]["episode"]]
    assert pairing.only_a == [a[1]["episode"]] and pairing.only_b == ["scene1/L0/t9#r9"]
    assert len(pairing.pairs) == len(a) - 3
    warnings = pairing.warnings("a", "b")
    assert any(a[0]["episode"] in w and "episode hashes differ" in w for w in warnings)
    assert any(a[2]["episode"] in w and "start tolerance" in w for w in warnings)


def test_holm_and_the_sign_flip_test():
    assert holm([0.01, 0.04, 0.03]) == pytest.approx([0.03, 0.06, 0.06])
    flat = paired_test(np.zeros(8), np.ones(8))
    assert flat.p == 1 and flat.interval == (0.0, 0.0)
    ahead = paired_test(np.full(8, 0.1), np.ones(8))
    assert ahead.p == pytest.approx(2 / 2 ** 8) and ahead.estimate == pytest.approx(0.1)


def test_compare_needs_episodes_and_says_so(tmp_path, capsys):
    empty = tmp_path / "empty"
    empty.mkdir()
    a = _run(tmp_path, "a", _records(4))
    assert main(["compare", str(a), str(empty)]) == 1
    err = capsys.readouterr().err
    assert "holds no evaluation run" in err and "Traceback" not in err
    assert main(["compare", str(a)]) == 2
    assert "compare takes at least two runs" in capsys.readouterr().err


def test_a_cell_whose_tasks_all_agree_gets_the_wilson_interval_over_its_tasks():
    episodes = [{"task": f"t{t}", "intent_score": 1.0, "execution_score": 0.5,
                 "complete": True} for t in range(16) for _ in range(10)]
    intervals = task_intervals(episodes)
    assert intervals["IS"] == wilson(1.0, 16) and intervals["CR"] == wilson(1.0, 16)
    assert intervals["ES"] == wilson(0.5, 16)
    assert task_intervals(episodes[:10])["IS"] is None  # one task: nothing over tasks


def test_compare_writes_a_page_with_a_forest_plot_per_metric(tmp_path):
    a = _run(tmp_path, "better", _records(5, shift=0.05))
    b = _run(tmp_path, "base", _records(5))
    out = tmp_path / "out"
    assert main(["compare", str(a), str(b), "--out", str(out)]) == 0
    page = (out / "compare.html").read_text()
    assert page.count("<svg") == 3  # IS, ES, CR
    assert "95% interval over tasks" in page and "scene1 L0 · 10 tasks" in page
    result = json.loads((out / "compare.json").read_text())
    assert result["verdicts"] == compare_runs(a, b)["verdicts"]
    assert (out / "compare.md").read_text() == markdown(compare_runs(a, b))


def _pilot(tmp_path, name, between, within, tasks=40, rounds=10, seed=0, scene="scene1"):
    """A one-level pilot: task means spread by `between`, rounds by `within` (0-1 scale)."""
    rng = np.random.default_rng(seed)
    records = []
    for task in range(tasks):
        mean = 0.5 + rng.normal(0, between)
        for round_index in range(1, rounds + 1):
            value = float(np.clip(mean + rng.normal(0, within), 0, 1))  # (scores' range)
            records.append({"episode": f"{scene}/L2/t{task}#r{round_index}", "scene": scene,
                            "level": "L2", "task": f"{scene}/L2/t{task}",
                            "hashes": {"episode": f"h{task}-{round_index}"},
                            "intent_score": value, "execution_score": value,
                            "complete": value > 0.5})
    return _run(tmp_path, name, records)


def test_the_power_plan_needs_more_rounds_for_smaller_differences_and_more_tasks_past_a_floor(
        tmp_path):
    from robofollow.eval.statistics.power import plan

    pilot = _pilot(tmp_path, "pilot", between=0.02, within=0.2)
    (entry,) = plan([run_scores(pilot)], 10.0)
    assert entry["tasks"] == 40 and entry["pilot_rounds"] == 10
    assert 15 < entry["within_sd"] < 25 and entry["between_sd"] < 5
    (smaller,) = plan([run_scores(pilot)], 5.0)
    assert smaller["rounds"] > entry["rounds"] >= 1
    spread = _pilot(tmp_path, "spread", between=0.3, within=0.05)  # tasks differ a lot
    (far,) = plan([run_scores(spread)], 5.0)
    assert far["rounds"] is None and far["tasks_needed"] > 40


def test_the_planned_rounds_give_about_the_planned_power(tmp_path):
    """Simulated paired comparisons at the planned rounds detect the planned difference about
    80% of the time (the sign-flip test over tasks, 5% two-sided)."""
    from robofollow.eval.statistics.power import plan

    rng = np.random.default_rng(11)
    tasks, between, within, delta = 30, 0.03, 0.25, 0.08
    (entry,) = plan([run_scores(_pilot(tmp_path, "pilot", between, within, tasks, 10, seed=3))],
                    100 * delta)
    rounds = entry["rounds"]
    detected = 0
    simulations = 120
    for _ in range(simulations):
        a = rng.normal(0, between, tasks)[:, None] + rng.normal(0, within, (tasks, rounds))
        b = rng.normal(0, between, tasks)[:, None] + rng.normal(0, within, (tasks, rounds))
        differences = (a - b).mean(axis=1) + delta
        detected += paired_test(differences, np.ones(tasks)).p < 0.05
    assert 0.65 <= detected / simulations <= 0.95, (rounds, detected)
    assert rounds > 1


def test_a_comparison_page_escapes_the_run_names(tmp_path):
    a = _run(tmp_path, "<script>alert(1)", _records(6, shift=0.05))
    b = _run(tmp_path, "base", _records(6))
    out = tmp_path / "out"
    assert main(["compare", str(a), str(b), "--out", str(out)]) == 0
    page = (out / "compare.html").read_text()
    assert "<script>" not in page and "&lt;script&gt;alert(1)" in page


def test_the_power_a_pilot_reaches_is_the_share_of_simulated_comparisons_that_detect_delta(
        tmp_path):
    """`reached`: the power of the pilot's own tasks and rounds, checked by simulating paired
    comparisons of that size (one pilot: a difference varies like two runs' scores)."""
    from robofollow.eval.statistics.power import plan

    tasks, rounds, between, within, delta = 30, 4, 0.05, 0.2, 0.08
    (entry,) = plan([run_scores(_pilot(tmp_path, "pilot", between, within, tasks, rounds,
                                       seed=5))], 100 * delta)
    rng = np.random.default_rng(7)
    simulations, detected = 200, 0
    for _ in range(simulations):
        scores = [rng.normal(0, entry["between_sd"] / 100, tasks)[:, None]
                  + rng.normal(0, entry["within_sd"] / 100, (tasks, rounds)) for _ in "ab"]
        differences = (scores[0] - scores[1]).mean(axis=1) + delta
        detected += paired_test(differences, np.ones(tasks)).p < 0.05
    assert 0.2 < entry["reached"] < 0.95
    assert abs(detected / simulations - entry["reached"]) < 0.15, (detected, entry)
    # more rounds than the pilot's were needed exactly when the pilot falls short of 80%
    assert (entry["rounds"] is not None and entry["rounds"] <= rounds) == (entry["reached"] >= 0.8)


def test_a_plan_by_cell_has_a_row_per_scene_and_level_and_says_what_each_reaches(tmp_path):
    from robofollow.eval.statistics.power import plan

    calm = run_scores(_pilot(tmp_path, "calm", between=0.02, within=0.1, seed=1))
    wild = [dict(row, scene="scene2", episode=row["episode"].replace("scene1", "scene2"),
                 task=row["task"].replace("scene1", "scene2"))
            for row in run_scores(_pilot(tmp_path, "wild", between=0.3, within=0.1, seed=2))]
    entries = plan([calm + wild], 10.0, by="cell")
    assert [e["cell"] for e in entries] == ["scene1 L2", "scene2 L2"]
    assert entries[0]["reached"] > 0.99 > 0.5 > entries[1]["reached"]
    assert entries[1]["rounds"] is None and entries[1]["tasks_needed"] > 40


def test_the_command_plans_by_cell_and_refuses_by_without_power(tmp_path, capsys):
    pilot = _pilot(tmp_path, "pilot", between=0.02, within=0.2)
    assert main(["compare", str(pilot), "--power", "10", "--by", "cell"]) == 0
    out = capsys.readouterr().out
    assert "| Cell | tasks |" in out and "| scene1 L2 | 40 | 10 |" in out and "power reached" in out
    assert main(["compare", str(pilot), str(pilot), "--by", "cell"]) == 2
    assert "--by shape the plan --power makes" in capsys.readouterr().err


def test_no_plan_is_made_from_pilots_that_share_no_episode_or_hold_one_round(tmp_path, capsys):
    """Two pilots with no episode in common, or a pilot of one round per task (its spread
    within a task unknown), get a one-line refusal, not an empty table or 'power 100%'."""
    pilot = _pilot(tmp_path, "pilot", between=0.1, within=0.2)
    other = _pilot(tmp_path, "other", between=0.1, within=0.2, scene="scene3")
    assert main(["compare", str(pilot), str(other), "--power", "10"]) == 1
    assert "the pilots share no episode" in capsys.readouterr().err
    single = _pilot(tmp_path, "single", between=0.1, within=0.2, rounds=1)
    assert main(["compare", str(single), "--power", "10"]) == 1
    err = capsys.readouterr().err
    assert "one round of every task of L2" in err and len(err.splitlines()) == 1
