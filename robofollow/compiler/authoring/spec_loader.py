"""Load .rf spec files into a validated Spec; report every problem at once.

Each problem is a SpecError with a code ('unknown-object', 'layout-cycle', ...) and the place it
was written; `load_spec` raises SpecErrors listing all of them. Loading goes on past a problem
without cascades: a body with a bad attribute is kept (with a stand-in value) so that later
uses of its name still resolve, and `load_partial` says which layouts hold such a body, have
a problem of poses or did not resolve, so that checks of the tasks on them (which would only
repeat the problem) are skipped while every other task is checked in the same run.

Files are read by spec_files.py, parsed by spec_parse.py and posed by layouts.py; checked
here are the scenes: bodies and their attributes, points, jitter, settings, tasks, listed
tests and split rules, and the counts of bodies and layouts (every number where it is written,
as spec_checks.py does).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from pathlib import Path

from lark import Token

from robofollow.compiler.authoring.footprints import Footprints
from robofollow.compiler.authoring.layouts import LayoutResolver
from robofollow.compiler.authoring.spec_files import (
    Sources,
    found_files,
    spec_text,
    split_lines,
)
from robofollow.compiler.authoring.spec_parse import parse_spec
from robofollow.compiler.authoring.spec_splits import SplitChecks
from robofollow.compiler.authoring.spec_syntax import (
    Attribute,
    BodyNode,
    ExpectNode,
    Interval,
    JitterNode,
    LayoutNode,
    Name,
    Number,
    PointNode,
    SceneNode,
    SettingNode,
    SplitNode,
    TaskNode,
    TestNode,
)
from robofollow.compiler.language import lf
from robofollow.compiler.language.parser import parse
from robofollow.compiler.scene.behaviour import Step
from robofollow.compiler.scene.observation import misnamed_twin
from robofollow.compiler.scene.spec import (
    FRICTION_RANGE,
    GUESS_MARGIN,
    GUESS_MARGIN_RANGE,
    HALF_EXTENT_RANGE,
    MASS_RANGE,
    MAX_BODIES,
    MAX_JITTER,
    MAX_LAYOUTS,
    RGB_RANGE,
    TABLE_HEIGHT,
    TABLE_HEIGHT_RANGE,
    YAW_RANGE,
    Body,
    Expected,
    Jitter,
    Layout,
    ListedTest,
    Scene,
    Source,
    Spec,
    Task,
)
from robofollow.errors import InstructionError, SpecError, SpecErrors

# per body kind: required size attributes -> half extents
_SIZES = {
    "cube": ("half",), "slab": ("half",), "label": ("half",),
    "cylinder": ("radius", "half_height"), "bowl": ("radius", "half_height"),
    "sphere": ("radius",),
}
_COMMON = ("color", "rgb")
_PHYSICS = ("mass", "friction")
_SETTINGS = {"table_height": TABLE_HEIGHT, "guess_margin": GUESS_MARGIN}
_SETTING_RANGES = {"table_height": (TABLE_HEIGHT_RANGE, " m"),
                   "guess_margin": (GUESS_MARGIN_RANGE, " Intent points")}


@dataclass
class Loaded:
    """What loading gave: the spec as far as it loaded, its problems, the lines of its files
    (for the errors of later checks), and per scene the layouts whose tasks are not worth
    checking (a body on them is broken, their poses have a problem, or they did not
    resolve)."""

    spec: Spec | None
    errors: list[SpecError]
    sources: Sources = field(default_factory=Sources)
    suspect: dict[str, set[str]] = field(default_factory=dict)


def load_partial(paths: list[Path] | Path) -> Loaded:
    """Parse and validate spec files, going on past problems (see the module docstring)."""
    return _Loader().load(found_files(paths))


def load_spec(paths: list[Path] | Path) -> Spec:
    """Parse and validate spec files; raise SpecErrors with every problem found."""
    loaded = load_partial(paths)
    if loaded.errors:
        raise SpecErrors(loaded.errors)
    return loaded.spec


class _Loader(SplitChecks):
    def __init__(self):
        super().__init__()
        self.labels: dict[str, Source] = {}  # task label -> where it is defined
        self.tests: dict[str, Source] = {}  # test id -> where it is defined
        self.scene_sources: dict[str, Source] = {}
        self.broken: set[str] = set()  # bodies of the current scene with a bad attribute
        self.suspect: dict[str, set[str]] = {}

    def load(self, files: list[tuple[Path, Path | None]]) -> Loaded:
        if not files:
            return Loaded(None, [SpecError("no-specs", "no .rf spec files found",
                                           file="<specs>", line=1, column=1)])
        digest = hashlib.sha256()
        scenes: dict[str, Scene] = {}
        for path, folder in files:
            self.file = str(path)
            text = spec_text(path, folder)
            if isinstance(text, SpecError):
                self.errors.append(text)
                continue
            digest.update(path.name.encode() + b"\0" + text.encode() + b"\0")
            self.sources.lines[self.file] = split_lines(text)
            nodes = parse_spec(text, self.file, self.sources)
            if isinstance(nodes, SpecError):
                self.errors.append(nodes)
                continue
            if not nodes:
                self.error("empty-spec", "no scene in this file (a spec file holds one or more "
                           "scene NAME \"title\" { ... } blocks)",
                           Source(file=self.file, line=1, column=1))
            for node in nodes:
                name = node.name
                if name in self.scene_sources:
                    self.error("duplicate-scene", f"scene {name!s} is also defined at "
                                                  f"{self.scene_sources[name]}", name)
                    continue
                self.scene_sources[str(name)] = self.source(name)
                scene = self.scene(node)
                if scene is not None:
                    scenes[scene.id] = scene
        return Loaded(Spec(scenes=scenes, digest=digest.hexdigest()), self.errors, self.sources,
                      self.suspect)

    # ---------------------------------------------------------------- scenes
    def scene(self, node: SceneNode) -> Scene | None:
        name, title = node.name, node.title
        self.broken = set()
        settings = dict(_SETTINGS)
        by_kind: dict[type, list] = {}
        for item in node.items:
            by_kind.setdefault(type(item), []).append(item)
        points, bad_points = self.points(by_kind.get(PointNode, []))
        seen_settings: set[str] = set()
        for item in by_kind.get(SettingNode, []):
            self.setting(item, settings, seen_settings)
        body_nodes, layout_nodes = by_kind.get(BodyNode, []), by_kind.get(LayoutNode, [])
        bodies: dict[str, Body] = {}
        for item in body_nodes:
            body = self.body(item)
            if body.id in bodies:  # the first stands, and what uses the name is not checked
                self.error("duplicate-object", f"{body.id!r} is defined twice", item.name)
                self.broken.add(body.id)
                continue
            bodies[body.id] = body
        # beyond a count limit the scene's layouts are not resolved (nor its tasks checked)
        too_many = False
        for nodes, limit, what in ((body_nodes, MAX_BODIES, "bodies"),
                                   (layout_nodes, MAX_LAYOUTS, "layouts")):
            if len(nodes) > limit:  # reported at the first one beyond the limit
                self.error(f"too-many-{what}", f"scene {name!s} declares {len(nodes)} {what}; "
                           f"at most {limit} are allowed", nodes[limit].name)
                too_many = True
        if not too_many:  # (pairwise: not for a scene beyond the limit)
            self.check_colours(bodies, body_nodes)
        jitter = self.jitters(by_kind.get(JitterNode, []), bodies)
        table = settings["table_height"]
        if too_many:
            layouts: dict[str, Layout] = {}
            defined = dict.fromkeys(str(item.name) for item in layout_nodes)
            troubled: set[str] = set()
        else:
            jitter_at = {str(item.target): item.target for item in by_kind.get(JitterNode, [])}
            resolver = LayoutResolver(self, bodies, points, bad_points, table,
                                      Footprints(bodies, jitter, jitter_at, self.broken))
            layouts = resolver.resolve(layout_nodes)
            # (in declaration order) a layout that failed to resolve is reported once, there
            defined = dict.fromkeys(resolver.raw)
            troubled = resolver.troubled
        if not by_kind.get(TaskNode):
            self.error("no-tasks", f"scene {name!s} has no training tasks (write at least one "
                       "task NAME on LAYOUT { \"instruction\" ... })", name)
        tasks = tuple(t for t in (self.task(item, str(name), bodies, defined)
                                  for item in by_kind.get(TaskNode, [])) if t is not None)
        tests = tuple(t for t in (self.test(item, str(name), bodies, defined)
                                  for item in by_kind.get(TestNode, [])) if t is not None)
        splits = {}
        for item in by_kind.get(SplitNode, []):
            rule = self.split(item, defined)
            if rule.level in splits:
                self.error("duplicate-split", f"two split rules for {rule.level}", item.level)
            splits[rule.level] = rule
        self.suspect[str(name)] = {layout for layout in defined if layout not in layouts
                                   or layout in troubled
                                   or any(body in self.broken for body in layouts[layout].placed)}
        scene = Scene(id=str(name), title=title[1:-1], bodies=bodies, points=points,
                      jitter=jitter, layouts=layouts, tasks=tasks, splits=splits, tests=tests,
                      table_height=table, guess_margin=settings["guess_margin"])
        self.repeated_layouts(scene, {str(item.name): item.name for item in layout_nodes},
                              self.suspect[scene.id])
        return scene

    def points(self, items: list[PointNode]
               ) -> tuple[dict[str, tuple[float, float]], set[str]]:
        """The named points, and those whose coordinates are bad (reported here, once: a layout
        that uses one fails without a second report)."""
        points: dict[str, tuple[float, float]] = {}
        bad: set[str] = set()
        for item in items:
            point = item.name
            if point in points or point in bad:
                self.error("duplicate-point", f"point {point!s} is defined twice", point)
                continue
            position = self.coordinates(item.coordinates, f"point {point!s}")
            if position is None:
                bad.add(str(point))
            else:
                points[str(point)] = position
        return points, bad

    def check_colours(self, bodies: dict[str, Body], items: list[BodyNode]) -> None:
        """Bodies that look the same (kind, size, rgb) must not be told apart by colour words
        a camera cannot see."""
        tokens = {str(item.name): item.name for item in items}
        seen: list[Body] = []
        for body in bodies.values():
            if body.id in self.broken:
                continue
            twin = misnamed_twin(body, seen)
            if twin is not None:
                self.error("colour-mismatch", f"{body.id} looks the same as {twin.id} (kind, "
                           f"size, rgb) but is called {body.color}, not {twin.color}",
                           tokens[body.id])
            seen.append(body)

    def setting(self, item: SettingNode, settings: dict[str, float], seen: set[str]) -> None:
        name = item.name
        if name not in settings:
            self.unknown_name("unknown-setting", "setting", name, settings)
            return
        if name in seen:
            self.error("duplicate-setting", f"{name!s} is set twice", name)
            return
        seen.add(str(name))
        if not isinstance(item.value, Number):
            self.error("bad-value", f"{name!s} takes a number", name)
            return
        bounds, unit = _SETTING_RANGES[str(name)]
        number = self.checked(item.value.token, str(name), bounds, unit)
        if number is not None:
            settings[str(name)] = number

    def body(self, item: BodyNode) -> Body:
        """The body as written; a bad or missing attribute is an error, and the body is kept
        with a stand-in value and marked broken (the checks of what rests on a stand-in would
        only repeat the error)."""
        name, kind, fixture = item.name, item.kind, item.fixture
        known = kind in _SIZES
        if not known:
            self.error("unknown-kind", f"unknown kind {kind!s} (expected one of: "
                                       f"{', '.join(_SIZES)})", kind)
            self.broken.add(str(name))
        sizes = _SIZES[str(kind)] if known else tuple(dict.fromkeys(
            a for names in _SIZES.values() for a in names))
        allowed = sizes + _COMMON + (() if fixture else _PHYSICS)
        errors_before = len(self.errors)
        found = self.attributes(item.attributes, allowed)
        missing = [a for a in allowed if a not in found and (known or a not in sizes)]
        if missing and len(self.errors) == errors_before:  # (else it may be one misspelt)
            self.error("missing-attribute", f"{name!s} needs {', '.join(missing)}", name)
        color = found["color"].value if "color" in found else None
        if color is not None and not isinstance(color, Name):
            self.error("bad-value", "color takes a colour name", found["color"].key)
        color = self.colour(color.token) if isinstance(color, Name) else None
        rgb = self.numbers(found["rgb"], 3, RGB_RANGE) if "rgb" in found else None
        half = self.size(str(kind), found) if known else None
        physics = {key: self.number(found[key], bounds, unit) for key, (bounds, unit) in
                   (("mass", (MASS_RANGE, " kg")), ("friction", (FRICTION_RANGE, "")))
                   if key in found}
        if color is None or half is None or rgb is None or None in physics.values():
            self.broken.add(str(name))
        return Body(id=str(name), kind=str(kind) if known else "cube", fixture=fixture,
                    color=color or "red",
                    rgb=rgb or (0.5, 0.5, 0.5), half_extents=half or (0.02, 0.02, 0.02),
                    **{key: value for key, value in physics.items() if value is not None})

    def size(self, kind: str, found: dict[str, Attribute]
             ) -> tuple[float, float, float] | None:
        """Half extents from a kind's size attributes (None when one is missing or bad)."""
        if any(a not in found for a in _SIZES[kind]):
            return None
        if kind in ("slab", "label"):
            return self.numbers(found["half"], 3, HALF_EXTENT_RANGE, " m")
        if kind == "cube":
            side = self.number(found["half"], HALF_EXTENT_RANGE, " m")
            return None if side is None else (side, side, side)
        radius = self.number(found["radius"], HALF_EXTENT_RANGE, " m")
        height = (self.number(found["half_height"], HALF_EXTENT_RANGE, " m")
                  if "half_height" in found else radius)
        return None if radius is None or height is None else (radius, radius, height)

    def jitters(self, items: list[JitterNode], bodies: dict[str, Body]) -> dict[str, Jitter]:
        """Jitter by body ('*': the default). A bad range is reported once: it stands as no
        jitter, and the bodies it applies to are marked broken."""
        jitter: dict[str, Jitter] = {}
        bad: set[str] = set()
        for item in items:
            target = item.target
            if target in jitter or target in bad:
                self.error("duplicate-jitter", f"the jitter of {target!s} is given twice",
                           target)
                continue
            if target != "*" and target not in bodies:
                self.unknown_name("unknown-object", "object", target, bodies)
            ranges = self.jitter(item.attributes)
            if ranges is None:
                bad.add(str(target))
            jitter[str(target)] = ranges or Jitter()
        for body in bodies:
            if body in bad or (body not in jitter and "*" in bad):
                self.broken.add(body)
        return jitter

    def jitter(self, attributes: tuple[Attribute, ...]) -> Jitter | None:
        found = self.attributes(attributes, ("x", "y"))
        ranges = {}
        ok = True
        for axis, node in found.items():
            value = node.value
            if not isinstance(value, Interval):
                self.error("bad-value", f"{axis} takes an interval [low, high] (m)", node.key)
                ok = False
                continue
            low, high = (self.checked(t, f"jitter {axis}", (-MAX_JITTER, MAX_JITTER), " m")
                         for t in (value.low, value.high))
            if low is None or high is None:
                ok = False
            elif low > high:
                self.error("bad-value", f"{axis} takes an interval [low, high] with low <= high",
                           node.key)
                ok = False
            else:
                ranges[axis] = (low, high)
        return Jitter(**ranges) if ok else None

    # ---------------------------------------------------------------- tasks and splits
    def task(self, item: TaskNode, scene: str, bodies: dict[str, Body],
             layouts: dict[str, None]) -> Task | None:
        label, layout, strings, expect = item.label, item.layout, item.strings, item.expect
        ok = True
        if label in self.labels:
            self.error("duplicate-label", f"task {label!s} is also defined at "
                                          f"{self.labels[label]}", label)
            ok = False
        self.labels.setdefault(str(label), self.source(label))
        if layout not in layouts:
            self.unknown_name("undefined-layout", "layout", layout, layouts, f" in {scene}")
            ok = False
        forms = [self.instruction(string) for string in strings]
        ok = ok and None not in forms
        expected = self.expected(expect, bodies) if expect is not None else None
        if not ok or (expect is not None and expected is None):
            return None
        return Task(label=str(label), scene=scene, layout=str(layout),
                    paraphrases=tuple(s[1:-1] for s in strings), forms=tuple(forms),
                    expect=expected, source=self.source(label),
                    paraphrase_sources=tuple(self.source(s) for s in strings))

    def instruction(self, string: Token):
        """The logical form of a quoted instruction, or None with its error reported at the
        word that causes it."""
        try:
            return parse(string[1:-1])
        except InstructionError as error:
            self.error(f"instruction-{error.code}", error.message,
                       Source(file=self.file, line=string.line,
                              column=string.column + error.column), error.length,
                       tuple(error.hints()))
            return None

    def test(self, item: TestNode, scene: str, bodies: dict[str, Body],
             layouts: dict[str, None]) -> ListedTest | None:
        level, name, layout, string, expect = (item.level, item.name, item.layout, item.string,
                                               item.expect)
        ok = True
        test_id = f"{scene}/{level}/{name}"
        if test_id in self.tests:
            self.error("duplicate-test", f"test {name!s} of {level!s} is also defined at "
                                         f"{self.tests[test_id]}", name)
            ok = False
        self.tests.setdefault(test_id, self.source(name))
        if layout not in layouts:
            self.unknown_name("undefined-layout", "layout", layout, layouts, f" in {scene}")
            ok = False
        ok = self.instruction(string) is not None and ok
        expected = self.expected(expect, bodies) if expect is not None else None
        if not ok or (expect is not None and expected is None):
            return None
        return ListedTest(name=str(name), scene=scene, level=str(level), layout=str(layout),
                          instruction=string[1:-1], expect=expected, source=self.source(name))

    def expected(self, node: ExpectNode, bodies: dict[str, Body]) -> Expected | None:
        steps = []
        errors_before = len(self.errors)
        for step in node.steps:
            if step.arm not in lf.Arm.__args__:
                self.error("bad-value", "the arm is 'left' or 'right'", step.arm)
            names = [step.source, *([step.target] if step.target is not None else ()),
                     *(w.name for w in step.waypoints)]
            for token in names:
                if token not in bodies:
                    self.unknown_name("unknown-object", "object", token, bodies)
            yaw = None if step.yaw is None else self.checked(step.yaw, "yaw", YAW_RANGE,
                                                             " degrees")
            steps.append({"action": step.action, "arm": str(step.arm),
                          "source": str(step.source),
                          "relation": None if step.relation is None else str(step.relation),
                          "target": None if step.target is None else str(step.target),
                          "waypoints": tuple(sorted((str(w.kind), str(w.name))
                                                    for w in step.waypoints)),
                          "yaw_degrees": yaw})
        if len(self.errors) > errors_before:
            return None
        return Expected(branch=None if node.branch is None else str(node.branch),
                        steps=tuple(Step(**s) for s in steps))
