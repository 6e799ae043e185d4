"""The benchmark as data: scene families, layouts, training tasks and split rules.

Built by spec_loader.py from the .rf files in specs/; frozen and validated. Positions are in
the world frame (metres): +x to the robot's right, +y away from the robot, +z up.
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping
from typing import Literal

from pydantic import Field

from robofollow.compiler.language import lf
from robofollow.compiler.scene.behaviour import Behaviour, Step
from robofollow.compiler.scene.model import Model
from robofollow.compiler.scene.workspace import TABLE_SIZE

BodyKind = Literal["cube", "slab", "cylinder", "sphere", "label", "bowl"]
TABLE_HEIGHT = 0.74  # m: the table top's height unless a scene sets it (upstream's)
Level = Literal["L0", "L1", "L2", "L3"]
LEVELS: tuple[Level, ...] = ("L0", "L1", "L2", "L3")
SPLIT_MOTIONS = ("any", "moved")  # a split rule's `motion=`: every task, or moved ones only
MOTION_LEVELS: tuple[Level, ...] = ("L1", "L3")  # the levels on changed layouts, which take it
# a split rule's `repeats=` (L1, L3): a layout it names that looks the same as a training layout
# is an error, or a distractor-free repeat the rule means
SPLIT_REPEATS = ("refused", "allowed")

# Limits on what a spec may say, checked when it is loaded (each value at its place in the
# file): physical bounds keep every number something the simulator, the expert and the
# cameras can handle; count limits keep a compile's time and memory bounded. Every number must
# also be finite. Positions (points, `at`, `move`) must lie on the table top (workspace.py:
# TABLE_SIZE, TABLE_CENTRE_Y); the loader then checks each body's footprint, with the jitter at
# its extremes, against the table's edges and the other bodies.
TABLE_HEIGHT_RANGE = (0.6, 0.9)  # m: the table top; the cameras are fixed (cam_high at 1.28 m)
HALF_EXTENT_RANGE = (0.0005, 0.2)  # m: a half size, radius or half height (the table is 1.2 m)
MASS_RANGE = (0.001, 10.0)  # kg: a ViperX lifts ~0.75 kg; heavier bodies can only be pushed
FRICTION_RANGE = (0.001, 10.0)  # MuJoCo's sliding friction coefficient
RGB_RANGE = (0.0, 1.0)  # each colour channel
YAW_RANGE = (-360.0, 360.0)  # deg: a placement's final yaw (`expect place ... yaw 90`)
JITTER_TABLE_FRACTION = 0.1  # a jitter bound is at most this fraction of the table's depth:
MAX_JITTER = round(JITTER_TABLE_FRACTION * min(TABLE_SIZE[:2]), 9)  # m (7 cm; nearer bodies are
#   kept apart by the overlap check with the jitter at its extremes)
ROUNDS = 10  # rounds per test task when a split rule does not say (`split ... rounds=`)
MAX_ROUNDS = 100  # `split ... rounds=`: rounds per test task
MAX_TASKS = 1000  # `split ... max=`: test tasks kept per level
MAX_SEED = 2_000_000_000  # `split ... seed=`: an episode's seed (seed + 100 x round + an
#   offset below 1000, splits.episode_seed) stays below 2**31
GUESS_MARGIN = 15.0  # Intent points: how far a cell's best language-blind guess may rise above
#   chance before the compile warns that the cell tells following from guessing poorly
GUESS_MARGIN_RANGE = (0.0, 100.0)  # Intent points (`set guess_margin`)
MAX_BODIES = 64  # objects and fixtures per scene
MAX_LAYOUTS = 256  # layouts per scene (a layout may derive from another: `layout b from a`)
MAX_STACK = 8  # bodies resting on (or in) one another, counting the one on the table
BOWL_FLOOR = 0.005  # m: height of a bowl's inner floor above its bottom
BOWL_WALL = 0.004  # m: a bowl's wall thickness (its radius is the wall's outside)
BOWL_SEGMENTS = 16  # flat wall boxes around a bowl (face normals every 360/16 deg from +x)
MAX_SPEC_BYTES = 4 * 1024 * 1024  # bytes per .rf file


class Source(Model):
    """Where something is written: file, 1-based line and column."""

    file: str
    line: int
    column: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.column}"


class Body(Model):
    """An object (movable) or a fixture (static: labels, bowls)."""

    id: str
    kind: BodyKind
    fixture: bool
    color: lf.Color
    rgb: tuple[float, float, float]
    half_extents: tuple[float, float, float]  # x, y, z; a sphere (r, r, r), a cylinder (r, r, h/2)
    mass: float | None = None
    friction: float | None = None

    @property
    def volume(self) -> float:
        """What 'larger' and 'smaller' compare (m^3)."""
        x, y, z = self.half_extents
        if self.kind == "sphere":
            return 4.0 / 3.0 * 3.141592653589793 * x ** 3
        if self.kind in ("cylinder", "bowl"):
            return 3.141592653589793 * x * x * 2 * z
        return 8 * x * y * z


class Jitter(Model):
    """Uniform offsets (m) added to a body's nominal x and y at episode start."""

    x: tuple[float, float] = (0.0, 0.0)
    y: tuple[float, float] = (0.0, 0.0)


class Placed(Model):
    """Where a body is in a layout: its nominal centre, and what it rests on or in."""

    x: float
    y: float
    z: float
    support: str | None = None
    relation: Literal["table", "on", "in"] = "table"


class Colour(Model):
    """A body's colour in a layout (`recolor`): its colour word and what the cameras see."""

    color: lf.Color
    rgb: tuple[float, float, float]


def shown(body: Body, colours: dict[str, Colour]) -> Body:
    """The body in the colour `colours` (a layout's, by body) give it, if they give one."""
    colour = colours.get(body.id)
    return body if colour is None else body.model_copy(update=colour.model_dump())


class Layout(Model):
    name: str
    base: str | None = None
    placed: dict[str, Placed]
    # by body: recoloured here or in a base (`recolor`)
    colours: dict[str, Colour] = Field(default_factory=dict)


class Expected(Model):
    """A behaviour as a task author writes it after `expect`."""

    branch: Literal["then", "otherwise"] | None = None
    steps: tuple[Step, ...]


class Task(Model):
    label: str
    scene: str
    layout: str
    paraphrases: tuple[str, ...]
    forms: tuple[lf.Instruction, ...]  # the parsed paraphrases, in order
    expect: Expected | None = None
    source: Source
    paraphrase_sources: tuple[Source, ...]


class ListedTest(Model):
    """A test task its author lists in a level: `test L2 name on layout { "..." expect ... }`."""

    name: str
    scene: str
    level: Level
    layout: str
    instruction: str
    expect: Expected | None = None
    source: Source

    @property
    def id(self) -> str:
        return f"{self.scene}/{self.level}/{self.name}"


class SplitRule(Model):
    level: Level
    layouts: tuple[str, ...] = ()
    wordings: tuple[str, ...] = ()
    max_tasks: int | None = None
    rounds: int = ROUNDS
    seed: int = 42
    # L1 / L3: "moved" keeps only tasks whose expert motion differs from the training task's
    # (an as-trained candidate is rejected); "any" keeps both, the paper's definition
    motion: Literal["any", "moved"] = "any"
    # L1 / L3: "allowed" lets the rule name a layout that looks the same as a training layout
    repeats: Literal["refused", "allowed"] = "refused"
    source: Source | None = None  # where the rule is written (left out of the scene's digest)


_LATER_SPLIT_FIELDS = ("motion", "repeats")  # left out of a scene's digest at their defaults


class Scene(Model):
    id: str
    title: str
    bodies: dict[str, Body]
    points: dict[str, tuple[float, float]]
    jitter: dict[str, Jitter]  # by body id; "*" is the default
    layouts: dict[str, Layout]
    tasks: tuple[Task, ...]
    splits: dict[str, SplitRule]
    tests: tuple[ListedTest, ...] = ()
    table_height: float = TABLE_HEIGHT
    guess_margin: float = GUESS_MARGIN  # Intent points (`set guess_margin`)

    def jitter_of(self, body: str) -> Jitter:
        return self.jitter.get(body) or self.jitter.get("*") or Jitter()

    def bodies_in(self, layout: str) -> dict[str, Body]:
        """The bodies a layout places, in its order, in their colours there."""
        chosen = self.layouts[layout]
        return {name: shown(self.bodies[name], chosen.colours) for name in chosen.placed}

    @property
    def digest(self) -> str:
        """sha256 over what the scene says (not where: file names and lines are left out), so
        a scene compiled alone or beside others, from any folder, has one digest. A split
        rule's default motion ("any") and repeats ("refused") are left out, and so are the
        colours of a layout that recolours nothing, as before these existed. The guess margin
        is left out: it decides no split and no episode, only a warning."""
        exclude: dict = {"tasks": {"__all__": {"source", "paraphrase_sources"}},
                         "tests": {"__all__": {"source"}}, "guess_margin": True}
        exclude["splits"] = {level: {"source"} | {
            key for key in _LATER_SPLIT_FIELDS
            if getattr(rule, key) == SplitRule.model_fields[key].default}
            for level, rule in self.splits.items()}
        uncoloured = {name: {"colours"} for name, layout in self.layouts.items()
                      if not layout.colours}
        if uncoloured:
            exclude["layouts"] = uncoloured
        data = self.model_dump_json(exclude=exclude)
        return hashlib.sha256(data.encode()).hexdigest()

    @property
    def training_layouts(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(task.layout for task in self.tasks))


class Spec(Model):
    scenes: dict[str, Scene]
    digest: str  # sha256 over the source files, in order

    @property
    def tasks(self) -> tuple[Task, ...]:
        return tuple(task for scene in self.scenes.values() for task in scene.tasks)


def scene_behaviours(spec: Spec, training: Mapping[str, Behaviour],
                     scene: str) -> dict[str, Behaviour]:
    """The scene's training behaviours by label, in the spec's order."""
    return {task.label: training[task.label] for task in spec.scenes[scene].tasks}
