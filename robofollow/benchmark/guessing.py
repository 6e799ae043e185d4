"""What a language-blind policy can earn in each test cell at best: on each layout of the cell,
the one training behaviour the layout allows that earns the most over the cell's tasks there
(chosen knowing them), performed perfectly. Beside it, the chance level: a uniform guess among
the behaviours each layout allows. Where the best guess rises far above chance, a policy that
ignores the words but happens to do the right thing on each layout scores well, and the cell
tells following from guessing apart poorly: such a cell is `guessable` when its best guess
exceeds chance by more than the scene's `guess_margin` (Intent points), and the layouts that
make it so are named, each with its guess and the tests that guess earns most on."""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.compiler.scene.spec import LEVELS, Scene, Spec, scene_behaviours
from robofollow.compiler.scene.world import World
from robofollow.compiler.splits.tasks import TestTask
from robofollow.oracle.chance import available_behaviours, earnings

NAMED_TESTS = 5  # tests named per layout in a guessable cell
EARNING = 0.5  # a test the guess earns at least this share of Intent on is named as earned


def blind_best(spec: Spec, training: Mapping[str, Behaviour],
               tasks: Iterable[TestTask]) -> dict[str, dict[str, dict]]:
    """{scene: {level: {"IS", "CR", "chance_IS", "chance_CR" (0-100), "layouts": [...]}}}: the
    best language-blind guess's mean Intent and completion rate over the cell's test tasks,
    a uniform guess's, and per layout (most guessable first) the guess that earns most Intent
    there, its mean Intent and chance's there, and the tests it earns at least EARNING of the
    Intent on (cells without tasks are left out)."""
    cells: dict[tuple[str, str], dict[str, list[TestTask]]] = defaultdict(
        lambda: defaultdict(list))
    for task in tasks:
        cells[task.scene, task.level][task.layout].append(task)
    found: dict[str, dict[str, dict]] = {}
    for scene_id, scene in spec.scenes.items():
        candidates = scene_behaviours(spec, training, scene_id)
        for level in LEVELS:
            layouts = cells.get((scene_id, level))
            if layouts:
                found.setdefault(scene_id, {})[level] = _cell(scene, candidates, layouts)
    return found


@dataclass(frozen=True)
class LayoutGuess:
    """The best blind guess on one layout of a cell: sums over the cell's tests there."""
    tests: int
    label: str  # the training behaviour it performs
    intent: float  # Intent earned (0-1 a test), summed
    completed: float  # tests it completes
    chance_intent: float  # a uniform guess's, summed
    chance_completed: float
    earning: tuple[str, ...]  # the tests it earns at least EARNING of the Intent on


def layout_guess(scene: Scene, candidates: Mapping[str, Behaviour], layout: str,
                 asked: list[TestTask]) -> LayoutGuess | None:
    """The guess that earns most Intent on a layout's tests (None where the layout allows no
    training behaviour)."""
    labels = available_behaviours(World(scene, layout), candidates)
    table = earnings([task.behaviour for task in asked], [candidates[label] for label in labels])
    if not table:
        return None
    intents = [sum(intent for intent, _ in row) for row in table]
    best = intents.index(max(intents))
    return LayoutGuess(
        tests=len(asked), label=labels[best], intent=intents[best],
        completed=max(float(sum(done for _, done in row)) for row in table),
        chance_intent=sum(intents) / len(table),
        chance_completed=sum(done for row in table for _, done in row) / len(table),
        earning=tuple(task.id for task, (intent, _) in zip(asked, table[best], strict=True)
                      if intent >= EARNING))


def _cell(scene: Scene, candidates: Mapping[str, Behaviour],
          layouts: Mapping[str, list[TestTask]]) -> dict:
    """One cell: the sums over its layouts, then per-task means (0-100)."""
    totals = {"IS": 0.0, "CR": 0.0, "chance_IS": 0.0, "chance_CR": 0.0}
    shown = []
    for layout, asked in layouts.items():
        guess = layout_guess(scene, candidates, layout, asked)
        if guess is None:
            continue
        totals["IS"] += guess.intent
        totals["CR"] += guess.completed
        totals["chance_IS"] += guess.chance_intent
        totals["chance_CR"] += guess.chance_completed
        shown.append((guess.intent - guess.chance_intent, {
            "layout": layout, "guess": guess.label, "tests": len(asked),
            "guess_IS": round(100 * guess.intent / len(asked), 1),
            "chance_IS": round(100 * guess.chance_intent / len(asked), 1),
            "earning": len(guess.earning), "earning_tests": list(guess.earning[:NAMED_TESTS])}))
    count = sum(len(asked) for asked in layouts.values())
    cell: dict = {metric: round(100 * value / count, 1) for metric, value in totals.items()}
    cell["layouts"] = [entry for _, entry in sorted(shown, key=lambda pair: -pair[0])]
    return cell


def guessable(spec: Spec, best: Mapping[str, Mapping[str, dict]]) -> list[dict]:
    """The cells whose best blind guess exceeds chance by more than the scene's guess margin:
    {"scene", "level", "IS", "chance_IS", "margin", "layouts"} (the layouts where the guess
    beats chance), in scene and level order."""
    found = []
    for scene_id, levels in best.items():
        margin = spec.scenes[scene_id].guess_margin
        for level, cell in levels.items():
            if cell["IS"] - cell["chance_IS"] > margin:
                found.append({"scene": scene_id, "level": level, "IS": cell["IS"],
                              "chance_IS": cell["chance_IS"], "margin": margin,
                              "layouts": [entry for entry in cell["layouts"]
                                          if entry["guess_IS"] > entry["chance_IS"]]})
    return found
