"""Counterbalance by search: test layouts for a scene whose L1 and L3 cells a language-blind
policy cannot pass by guessing.

The bodies the training tasks handle stay where the base layout puts them (the points the
training set picks from); the other bodies that stand alone on the table trade places over
candidate spots, each arrangement a candidate layout. All candidates are compiled at once, as
the scene's L1 and L3 layouts without a cap, and each is measured per level: its tests, the
tests whose motion changed, and the Intent the best blind guess and chance earn there
(`guessing.layout_guess`). Cells sum over their layouts, so a selection's figures are linear in
which layouts it takes: an exact integer program (scipy's `milp`) picks the fewest layouts that
meet the bounds, or, where none do, the lowest margin over chance any selection reaches.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from robofollow.benchmark.guessing import layout_guess
from robofollow.compiler.authoring.footprints import overlap_depth, past_edge
from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.compiler.scene.spec import Layout, Placed, Scene, Spec, scene_behaviours
from robofollow.compiler.splits.generator import generate_examined
from robofollow.errors import RoboFollowError

SEARCHED_LEVELS = ("L1", "L3")
SPOT_SPACING = 0.06  # m: candidate spots closer than this to one another are one spot
MARGIN_STEP = 0.5  # Intent points: how finely the lowest reachable margin is searched
MEASURED_AT_ONCE = 25  # candidate layouts compiled together


@dataclass(frozen=True)
class Bounds:
    """What every searched cell of a selection must meet."""
    margin: float = 15.0  # the best blind guess at most this many Intent points over chance
    guess: float = 35.0  # and at most this Intent
    tests: Mapping[str, int] = field(default_factory=lambda: {"L1": 40, "L3": 40})
    moved: Mapping[str, int] = field(default_factory=lambda: {"L1": 20})  # changed motions


@dataclass(frozen=True)
class Measured:
    """One candidate layout's share of one cell (sums, not means)."""
    tests: int
    moved: int
    guess: float  # the best blind guess's Intent there (0-1 a test, summed)
    chance: float


@dataclass(frozen=True)
class Candidate:
    name: str
    moves: tuple[tuple[str, tuple[float, float]], ...]  # (body, where it stands)
    cells: Mapping[str, Measured]  # by level


@dataclass(frozen=True)
class Selection:
    layouts: tuple[str, ...]
    cells: Mapping[str, dict]  # by level: tests, moved, guess and chance (Intent, 0-100)
    meets: bool  # whether it meets the bounds; else it is the lowest margin found
    margin: float  # the highest margin over chance of its cells


def handled(scene: Scene, training: Mapping[str, Behaviour]) -> set[str]:
    """The bodies some training step of the scene moves."""
    return {step.source for task in scene.tasks for step in training[task.label].steps}


def movable_landmarks(scene: Scene, base: str, kept: set[str]) -> list[str]:
    """The bodies of the base layout that may trade places: on the table, carrying nothing,
    and not kept."""
    placed = scene.layouts[base].placed
    carriers = {p.support for p in placed.values() if p.support is not None}
    return [b for b, p in placed.items()
            if p.support is None and b not in kept and b not in carriers]


def default_spots(scene: Scene, base: str, bodies: Sequence[str]) -> list[tuple[float, float]]:
    """Where the moving bodies stand in any of the scene's layouts, one spot per place."""
    found: list[tuple[float, float]] = []
    for layout in scene.layouts.values():
        for body in bodies:
            at = layout.placed.get(body)
            if at is not None and at.support is None:
                found.append((at.x, at.y))
    return distinct(found)


def distinct(spots: Sequence[tuple[float, float]]) -> list[tuple[float, float]]:
    kept: list[tuple[float, float]] = []
    for spot in spots:
        if all(math.dist(spot, other) >= SPOT_SPACING for other in kept):
            kept.append((round(spot[0], 4), round(spot[1], 4)))
    return kept


def arrangements(scene: Scene, base: str, bodies: Sequence[str],
                 spots: Sequence[tuple[float, float]]) -> list[dict[str, Placed]]:
    """The base layout with `bodies` over `spots` (each in one spot, none over another body's
    footprint or off the table at the jitter extremes), the base's own arrangement left out,
    in a fixed order."""
    placed = scene.layouts[base].placed
    found = []
    for chosen in itertools.permutations(spots, len(bodies)):
        trial = dict(placed)
        for body, (x, y) in zip(bodies, chosen, strict=True):
            trial[body] = placed[body].model_copy(update={"x": x, "y": y})
        if all(math.isclose(trial[b].x, placed[b].x) and math.isclose(trial[b].y, placed[b].y)
               for b in bodies) or not _fits(scene, trial, bodies):
            continue
        found.append(trial)
    return found


def _fits(scene: Scene, placed: Mapping[str, Placed], moved: Sequence[str]) -> bool:
    for body in moved:
        spec, at, jitter = scene.bodies[body], placed[body], scene.jitter_of(body)
        if past_edge(spec, at, jitter) > 0:
            return False
        for other, there in placed.items():
            if other != body and there.support is None and overlap_depth(
                    spec, at, scene.bodies[other], there, jitter, scene.jitter_of(other)) > 0:
                return False
    return True


def measure(spec: Spec, scene_id: str, training: Mapping[str, Behaviour],
            layouts: Sequence[dict[str, Placed]], base: str, moving: Sequence[str],
            progress: bool = False) -> list[Candidate]:
    """Compile every candidate layout as the scene's L1 and L3 layouts, uncapped, and measure
    each one's share of each cell (MEASURED_AT_ONCE candidates a compile: a layout's tests do
    not depend on the others')."""
    from tqdm import tqdm

    scene = spec.scenes[scene_id]
    missing = [level for level in SEARCHED_LEVELS if level not in scene.splits]
    if missing:
        raise RoboFollowError(f"scene {scene_id} has no {' or '.join(missing)} split rule: "
                              "the search proposes layouts for its L1 and L3 rules")
    names = [f"search_{number:03d}" for number in range(1, len(layouts) + 1)]
    found = []
    with tqdm(total=len(names), desc="candidates", unit="layout", disable=not progress) as bar:
        for start in range(0, len(names), MEASURED_AT_ONCE):
            part = slice(start, start + MEASURED_AT_ONCE)
            found += _measured(spec, scene_id, training, layouts[part], names[part], base,
                               moving)
            bar.update(len(names[part]))
    return found


def _measured(spec: Spec, scene_id: str, training: Mapping[str, Behaviour],
              layouts: Sequence[dict[str, Placed]], names: Sequence[str], base: str,
              moving: Sequence[str]) -> list[Candidate]:
    scene = spec.scenes[scene_id]
    added = {name: Layout(name=name, base=base, placed=placed,
                          colours=scene.layouts[base].colours)
             for name, placed in zip(names, layouts, strict=True)}
    rules = {level: scene.splits[level].model_copy(update={"layouts": tuple(names),
                                                           "max_tasks": None})
             for level in SEARCHED_LEVELS}
    searched = scene.model_copy(update={"layouts": {**scene.layouts, **added},
                                        "splits": {**scene.splits, **rules}, "tests": ()})
    alone = Spec(scenes={scene_id: searched}, digest=spec.digest)
    splits, _ = generate_examined(alone, dict(training), levels=SEARCHED_LEVELS)
    behaviours = scene_behaviours(alone, training, scene_id)
    by_cell: dict[tuple[str, str], list] = {}
    for task in splits.tasks:
        by_cell.setdefault((task.level, task.layout), []).append(task)
    candidates = []
    for name, placed in zip(names, layouts, strict=True):
        cells = {}
        for level in SEARCHED_LEVELS:
            asked = by_cell.get((level, name), [])
            guess = layout_guess(searched, behaviours, name, asked) if asked else None
            cells[level] = Measured(
                tests=len(asked), moved=sum(task.motion == "moved" for task in asked),
                guess=guess.intent if guess else 0.0, chance=guess.chance_intent if guess else 0.0)
        base_placed = scene.layouts[base].placed
        candidates.append(Candidate(name=name, cells=cells, moves=tuple(
            (body, (placed[body].x, placed[body].y)) for body in moving
            if (placed[body].x, placed[body].y) != (base_placed[body].x, base_placed[body].y))))
    return candidates


def select(candidates: Sequence[Candidate], bounds: Bounds) -> Selection | None:
    """The fewest layouts whose cells meet `bounds`; where none do, the selection with the
    lowest margin over chance (searched in MARGIN_STEP steps) meeting the other bounds, or
    None where even that is out of reach."""
    chosen = _solve(candidates, bounds)
    if chosen is not None:
        return _selection(candidates, chosen, True)
    low, high = bounds.margin, 100.0
    if _solve(candidates, _relaxed(bounds, high)) is None:
        return None
    while high - low > MARGIN_STEP:
        middle = (low + high) / 2
        if _solve(candidates, _relaxed(bounds, middle)) is None:
            low = middle
        else:
            high = middle
    return _selection(candidates, _solve(candidates, _relaxed(bounds, high)), False)


def _relaxed(bounds: Bounds, margin: float) -> Bounds:
    return Bounds(margin=margin, guess=100.0, tests=bounds.tests, moved=bounds.moved)


def _solve(candidates: Sequence[Candidate], bounds: Bounds) -> list[int] | None:
    """The integer program: x_i = 1 takes candidate i; per cell, linear in x,
    tests >= bound, moved >= bound, guess - chance <= margin * tests, guess <= cap * tests;
    fewest layouts, then the least guess over chance."""
    from scipy.optimize import Bounds as Box
    from scipy.optimize import LinearConstraint, milp

    if not candidates:
        return None
    rows, lower, upper = [], [], []
    for level in SEARCHED_LEVELS:
        cells = [c.cells[level] for c in candidates]
        tests = np.array([m.tests for m in cells], dtype=float)
        rows.append(tests)
        lower.append(bounds.tests.get(level, 0))
        upper.append(np.inf)
        rows.append(np.array([m.moved for m in cells], dtype=float))
        lower.append(bounds.moved.get(level, 0))
        upper.append(np.inf)
        over = np.array([m.guess - m.chance for m in cells])
        rows.append(100 * over - bounds.margin * tests)
        lower.append(-np.inf)
        upper.append(0.0)
        rows.append(100 * np.array([m.guess for m in cells]) - bounds.guess * tests)
        lower.append(-np.inf)
        upper.append(0.0)
    over_all = sum(np.array([c.cells[level].guess - c.cells[level].chance for c in candidates])
                   for level in SEARCHED_LEVELS)
    tests_all = sum(c.cells[level].tests for c in candidates for level in SEARCHED_LEVELS) or 1
    cost = 1.0 + np.clip(over_all, 0, None) / tests_all  # a layout first, then its guessing
    result = milp(cost, integrality=np.ones(len(candidates)), bounds=Box(0, 1),
                  constraints=LinearConstraint(np.array(rows), lower, upper))
    if not result.success:
        return None
    return [i for i, x in enumerate(result.x) if x > 0.5]


def _selection(candidates: Sequence[Candidate], chosen: list[int], meets: bool) -> Selection:
    cells = {}
    for level in SEARCHED_LEVELS:
        measured = [candidates[i].cells[level] for i in chosen]
        tests = sum(m.tests for m in measured)
        guess = 100 * sum(m.guess for m in measured) / max(tests, 1)
        chance = 100 * sum(m.chance for m in measured) / max(tests, 1)
        cells[level] = {"tests": tests, "moved": sum(m.moved for m in measured),
                        "guess_IS": round(guess, 1), "chance_IS": round(chance, 1)}
    margin = max(cell["guess_IS"] - cell["chance_IS"] for cell in cells.values())
    return Selection(layouts=tuple(candidates[i].name for i in chosen), cells=cells,
                     meets=meets, margin=round(margin, 1))


def layout_statements(base: str, candidates: Sequence[Candidate],
                      names: Sequence[str]) -> list[str]:
    """The selected layouts as spec statements to paste into the scene."""
    by_name = {c.name: c for c in candidates}
    lines = []
    for name in names:
        lines.append(f"layout {name} from {base} {{")
        lines += [f"    move {body} to ({x:g}, {y:g})" for body, (x, y) in by_name[name].moves]
        lines.append("}")
    return lines


@dataclass(frozen=True)
class Proposal:
    base: str
    kept: tuple[str, ...]  # the handled bodies, where the base puts them
    moving: tuple[str, ...]
    spots: tuple[tuple[float, float], ...]
    candidates: tuple[Candidate, ...]
    selection: Selection | None


def propose(spec: Spec, scene_id: str, training: Mapping[str, Behaviour], base: str | None = None,
            spots: Sequence[tuple[float, float]] = (), keep: Sequence[str] = (),
            limit: int = 1000, seed: int = 0, bounds: Bounds = Bounds(),
            progress: bool = False) -> Proposal:
    """Search a scene's test layouts: the handled bodies (and `keep`) stay at the base layout
    (default: the first training layout), the others trade places over the base's own spots
    and `spots`; at most `limit` candidates, a seeded sample where there are more."""
    scene = spec.scenes[scene_id]
    base = base or scene.training_layouts[0]
    kept = handled(scene, training) | set(keep)
    moving = movable_landmarks(scene, base, kept)
    if not moving:
        raise RoboFollowError(f"in layout {base} of scene {scene_id} every body on the table "
                              "is handled by a training task or kept: nothing can move")
    where = distinct([*default_spots(scene, base, moving), *spots])
    found = arrangements(scene, base, moving, where)
    if len(found) > limit:
        rng = np.random.default_rng(seed)
        found = [found[i] for i in sorted(rng.choice(len(found), limit, replace=False))]
    candidates = measure(spec, scene_id, training, found, base, moving, progress)
    return Proposal(base=base, kept=tuple(sorted(kept)), moving=tuple(moving),
                    spots=tuple(where), candidates=tuple(candidates),
                    selection=select(candidates, bounds))
