"""Load .rf spec files into a validated Spec; report every problem at once.

Each problem is a SpecError with a code ('unknown-object', 'layout-cycle', ...) and the place it
was written; `load_spec` raises SpecErrors listing all of them. Loading goes on past a problem
without cascades: a body with a bad attribute is kept (with a stand-in value) so that later
uses of its name still resolve, and `load_partial` says which layouts hold such a body or did
not resolve, so that checks of the tasks on them (which would only repeat the problem) are
skipped while every other task is checked in the same run.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, field
from functools import cache, lru_cache
from pathlib import Path

from lark import Lark, Token, Tree, UnexpectedCharacters, UnexpectedEOF, UnexpectedToken

from robofollow.compiler import lf
from robofollow.compiler.behaviour import Step
from robofollow.compiler.observation import looks_alike
from robofollow.compiler.parser import parse
from robofollow.compiler.spec import (
    Body,
    Expected,
    Jitter,
    Layout,
    ListedTest,
    Placed,
    Scene,
    Source,
    Spec,
    SplitRule,
    Task,
)
from robofollow.compiler.workspace import table_bounds
from robofollow.errors import InstructionError, SpecError, SpecErrors
from robofollow.resources import grammar_text

SPEC_SUFFIX = ".rf"
WORDINGS = frozenset({"referents", "routes", "orientation", "conditions", "branches"})
BOWL_FLOOR = 0.005  # m: height of a bowl's inner floor above its bottom

# per body kind: required size attributes -> half extents
_SIZES = {
    "cube": ("half",), "slab": ("half",), "label": ("half",),
    "cylinder": ("radius", "half_height"), "bowl": ("radius", "half_height"),
    "sphere": ("radius",),
}
_COMMON = ("color", "rgb")
_PHYSICS = ("mass", "friction")
_SETTINGS = {"table_height": 0.74}


@lru_cache(maxsize=64)
def _file_lines(file: str) -> tuple[str, ...]:
    try:
        return tuple(Path(file).read_text(encoding="utf-8").splitlines())
    except OSError:
        return ()


def spec_error(code: str, message: str, where: Source, length: int = 1,
               lines: list[str] | tuple[str, ...] | None = None) -> SpecError:
    """A SpecError showing the source line (from `lines`, else read from the file)."""
    lines = _file_lines(where.file) if lines is None else lines
    source_line = lines[where.line - 1] if 0 < where.line <= len(lines) else ""
    return SpecError(code, message, file=where.file, line=where.line, column=where.column,
                     source_line=source_line, length=length)


@cache
def _parser() -> Lark:
    return Lark(grammar_text("spec.lark"), parser="lalr", strict=True, propagate_positions=True)


def spec_files(paths: list[Path] | Path) -> list[Path]:
    """The .rf files named, or found below the folders named, in a stable order."""
    files: list[Path] = []
    for path in [paths] if isinstance(paths, Path) else paths:
        files.extend(sorted(path.rglob(f"*{SPEC_SUFFIX}")) if path.is_dir() else [path])
    return files


@dataclass
class Loaded:
    """What loading gave: the spec as far as it loaded, its problems, and per scene the
    layouts whose tasks are not worth checking (a body on them is broken, or they did not
    resolve)."""

    spec: Spec | None
    errors: list[SpecError]
    suspect: dict[str, set[str]] = field(default_factory=dict)


def load_partial(paths: list[Path] | Path) -> Loaded:
    """Parse and validate spec files, going on past problems (see the module docstring)."""
    return _Loader().load(spec_files(paths))


def load_spec(paths: list[Path] | Path) -> Spec:
    """Parse and validate spec files; raise SpecErrors with every problem found."""
    loaded = load_partial(paths)
    if loaded.errors:
        raise SpecErrors(loaded.errors)
    return loaded.spec


class _Loader:
    def __init__(self):
        self.errors: list[SpecError] = []
        self.lines: dict[str, list[str]] = {}
        self.file = ""
        self.labels: dict[str, Source] = {}  # task label -> where it is defined
        self.tests: dict[str, Source] = {}  # test id -> where it is defined
        self.scene_sources: dict[str, Source] = {}
        self.broken: set[str] = set()  # bodies of the current scene with a bad attribute
        self.suspect: dict[str, set[str]] = {}

    # ---------------------------------------------------------------- errors
    def error(self, code: str, message: str, where: Token | Tree | Source, length: int | None = None):
        if isinstance(where, Source):
            file, line, column, size = where.file, where.line, where.column, 1
        elif isinstance(where, Token):
            file, line, column, size = self.file, where.line, where.column, len(where)
        else:
            file, line, column = self.file, where.meta.line, where.meta.column
            size = 1
        self.errors.append(spec_error(code, message, Source(file=file, line=line, column=column),
                                      length or size, self.lines.get(file, [])))

    def source(self, token: Token) -> Source:
        return Source(file=self.file, line=token.line, column=token.column)

    # ---------------------------------------------------------------- files
    def load(self, files: list[Path]) -> Loaded:
        if not files:
            return Loaded(None, [SpecError("no-specs", "no .rf spec files found",
                                           file="<specs>", line=1, column=1)])
        digest = hashlib.sha256()
        scenes: dict[str, Scene] = {}
        for path in files:
            self.file = str(path)
            try:
                text = path.read_text(encoding="utf-8")
            except (OSError, UnicodeDecodeError) as error:
                self.errors.append(SpecError("unreadable", str(error), file=self.file, line=1,
                                             column=1))
                continue
            digest.update(path.name.encode() + b"\0" + text.encode() + b"\0")
            self.lines[self.file] = text.splitlines()
            tree = self.syntax(text)
            for node in tree.children if tree is not None else ():
                name = node.children[0]
                if name in self.scene_sources:
                    self.error("duplicate-scene", f"scene {name!s} is also defined at "
                                                  f"{self.scene_sources[name]}", name)
                    continue
                self.scene_sources[str(name)] = self.source(name)
                scene = self.scene(node)
                if scene is not None:
                    scenes[scene.id] = scene
        return Loaded(Spec(scenes=scenes, digest=digest.hexdigest()), self.errors, self.suspect)

    def syntax(self, text: str) -> Tree | None:
        try:
            return _parser().parse(text)
        except (UnexpectedEOF, UnexpectedToken) as error:
            if isinstance(error, UnexpectedEOF) or error.token.type == "$END":
                lines = text.rstrip().splitlines() or [""]
                self.errors.append(SpecError(
                    "syntax", "the file ends too early" + _expected(error.expected),
                    file=self.file, line=len(lines), column=len(lines[-1]) + 1,
                    source_line=lines[-1]))
            else:
                self.error("syntax", f"unexpected {error.token!s:.30}"
                           + _expected(error.expected), error.token)
        except UnexpectedCharacters as error:
            self.error("syntax", f"unexpected character {text[error.pos_in_stream]!r}"
                       + _expected(error.allowed), Source(file=self.file, line=error.line,
                                                          column=error.column))
        return None

    # ---------------------------------------------------------------- scenes
    def scene(self, node: Tree) -> Scene | None:
        name, title, *items = node.children
        self.broken = set()
        points: dict[str, tuple[float, float]] = {}
        bodies: dict[str, Body] = {}
        settings = dict(_SETTINGS)
        by_kind: dict[str, list[Tree]] = {}
        for item in items:
            by_kind.setdefault(item.data, []).append(item)
        for item in by_kind.get("point", []):
            point, coordinates = item.children
            if point in points:
                self.error("duplicate-point", f"point {point!s} is defined twice", point)
            points[str(point)] = _coordinates(coordinates)
        for item in by_kind.get("setting", []):
            self.setting(item, settings)
        for item in by_kind.get("body", []):
            body = self.body(item)
            if body.id in bodies:
                self.error("duplicate-object", f"{body.id!r} is defined twice", item.children[1])
            bodies[body.id] = body
        self.check_colours(bodies, by_kind.get("body", []))
        jitter = {}
        for item in by_kind.get("jitter", []):
            target, attributes = item.children[0], item.children[1:]
            if target != "*" and target not in bodies:
                self.error("unknown-object", f"no object named {target!s}", target)
            jitter[str(target)] = self.jitter(attributes)
        table = settings["table_height"]
        resolver = _LayoutResolver(self, bodies, points, table, jitter)
        layouts = resolver.resolve(by_kind.get("layout", []))
        defined = set(resolver.raw)  # a layout that failed to resolve is reported once, there
        tasks = tuple(t for t in (self.task(item, str(name), bodies, defined)
                                  for item in by_kind.get("task", [])) if t is not None)
        tests = tuple(t for t in (self.test(item, str(name), bodies, defined)
                                  for item in by_kind.get("test", [])) if t is not None)
        splits = {}
        for item in by_kind.get("split", []):
            rule = self.split(item, defined)
            if rule.level in splits:
                self.error("duplicate-split", f"two split rules for {rule.level}", item.children[0])
            splits[rule.level] = rule
        self.suspect[str(name)] = {layout for layout in defined if layout not in layouts or any(
            body in self.broken for body in layouts[layout].placed)}
        return Scene(id=str(name), title=title[1:-1], bodies=bodies, points=points, jitter=jitter,
                     layouts=layouts, tasks=tasks, splits=splits, tests=tests,
                     table_height=table)

    def check_colours(self, bodies: dict[str, Body], items: list[Tree]) -> None:
        """Bodies that look the same (kind, size, rgb) must not be told apart by colour words
        a camera cannot see."""
        tokens = {str(item.children[1]): item.children[1] for item in items}
        seen: list[Body] = []
        for body in bodies.values():
            twin = next((b for b in seen if looks_alike(b, body) and b.color != body.color), None)
            if twin is not None and body.id not in self.broken:
                self.error("colour-mismatch", f"{body.id} looks the same as {twin.id} (kind, "
                           f"size, rgb) but is called {body.color}, not {twin.color}",
                           tokens[body.id])
            seen.append(body)

    def setting(self, item: Tree, settings: dict[str, float]) -> None:
        name, value = item.children
        if name not in settings:
            self.error("unknown-setting", f"unknown setting {name!s} (known: "
                                          f"{', '.join(sorted(settings))})", name)
        elif value.data != "number":
            self.error("bad-value", f"{name!s} takes a number", name)
        else:
            settings[str(name)] = float(value.children[0])

    def attributes(self, nodes: list[Tree], allowed: tuple[str, ...]) -> dict[str, Tree]:
        found: dict[str, Tree] = {}
        for node in nodes:
            key = node.children[0]
            if key not in allowed:
                self.error("unknown-attribute", f"unknown attribute {key!s} here (expected one "
                                                f"of: {', '.join(allowed)})", key)
            elif key in found:
                self.error("duplicate-attribute", f"{key!s} is given twice", key)
            else:
                found[str(key)] = node
        return found

    def number(self, node: Tree, low: float = -math.inf, high: float = math.inf) -> float | None:
        value = node.children[1]
        if value.data != "number":
            self.error("bad-value", f"{node.children[0]!s} takes a number", node.children[0])
            return None
        number = float(value.children[0])
        if not low <= number <= high:
            self.error("bad-value", f"{node.children[0]!s} must be in [{low}, {high}]",
                       value.children[0])
            return None
        return number

    def numbers(self, node: Tree, count: int | None, low=-math.inf, high=math.inf):
        value = node.children[1]
        items = value.children if value.data == "values" else [value]
        numbers = [float(i.children[0]) for i in items if i.data == "number"]
        if len(numbers) != len(items) or (count is not None and len(numbers) != count) or not all(
                low <= n <= high for n in numbers):
            size = f"{count} numbers" if count else "numbers"
            self.error("bad-value", f"{node.children[0]!s} takes {size} in [{low}, {high}]",
                       node.children[0])
            return None
        return tuple(numbers)

    def body(self, item: Tree) -> Body:
        """The body as written; a bad or missing attribute is an error, and the body is kept
        with a stand-in value (marked broken when the value could change what words mean)."""
        kind_node, name, kind, *attribute_nodes = item.children
        fixture = kind_node.children[0] == "fixture"
        if kind not in _SIZES:
            self.error("unknown-kind", f"unknown kind {kind!s} (expected one of: "
                                       f"{', '.join(_SIZES)})", kind)
            self.broken.add(str(name))
            kind = "cube"
        allowed = _SIZES[str(kind)] + _COMMON + (() if fixture else _PHYSICS)
        found = self.attributes(attribute_nodes, allowed)
        missing = [a for a in allowed if a not in found]
        if missing:
            self.error("missing-attribute", f"{name!s} needs {', '.join(missing)}", name)
        color = found["color"].children[1] if "color" in found else None
        if color is not None and (color.data != "name"
                                  or color.children[0] not in lf.Color.__args__):
            where = color.children[0] if color.data == "name" else found["color"].children[0]
            self.error("bad-value", f"color must be one of {', '.join(lf.Color.__args__)}", where)
            color = None
        rgb = self.numbers(found["rgb"], 3, 0.0, 1.0) if "rgb" in found else None
        half = self.size(str(kind), found)
        physics = {key: self.number(found[key], 1e-6, 100.0) for key in _PHYSICS if key in found}
        if color is None or half is None:
            self.broken.add(str(name))
        return Body(id=str(name), kind=str(kind), fixture=fixture,
                    color=str(color.children[0]) if color is not None else "red",
                    rgb=rgb or (0.5, 0.5, 0.5), half_extents=half or (0.02, 0.02, 0.02),
                    **{key: value for key, value in physics.items() if value is not None})

    def size(self, kind: str, found: dict[str, Tree]) -> tuple[float, float, float] | None:
        """Half extents from a kind's size attributes (None when one is missing or bad)."""
        if any(a not in found for a in _SIZES[kind]):
            return None
        if kind in ("slab", "label"):
            return self.numbers(found["half"], 3, 0.0005, 1.0)
        if kind == "cube":
            side = self.number(found["half"], 0.0005, 1.0)
            return None if side is None else (side, side, side)
        radius = self.number(found["radius"], 0.0005, 1.0)
        height = (self.number(found["half_height"], 0.0005, 1.0) if "half_height" in found
                  else radius)
        return None if radius is None or height is None else (radius, radius, height)

    def jitter(self, attributes: list[Tree]) -> Jitter:
        found = self.attributes(attributes, ("x", "y"))
        ranges = {}
        for axis, node in found.items():
            value = node.children[1]
            low, high = (float(t) for t in value.children) if value.data == "interval" else (1, 0)
            if low > high:
                self.error("bad-value", f"{axis} takes an interval [low, high]", node.children[0])
            ranges[axis] = (low, high)
        return Jitter(**ranges)

    # ---------------------------------------------------------------- tasks and splits
    def task(self, item: Tree, scene: str, bodies: dict[str, Body],
             layouts: set[str]) -> Task | None:
        label, layout, *rest = item.children
        strings = [t for t in rest if isinstance(t, Token)]
        expect = next((t for t in rest if isinstance(t, Tree)), None)
        ok = True
        if label in self.labels:
            self.error("duplicate-label", f"task {label!s} is also defined at "
                                          f"{self.labels[label]}", label)
            ok = False
        self.labels.setdefault(str(label), self.source(label))
        if layout not in layouts:
            self.error("undefined-layout", f"no layout named {layout!s} in {scene}", layout)
            ok = False
        forms = []
        for string in strings:
            try:
                forms.append(parse(string[1:-1]))
            except InstructionError as error:
                self.error(f"instruction-{error.code}", error.message,
                           Source(file=self.file, line=string.line,
                                  column=string.column + error.column), error.length)
                ok = False
        expected = self.expected(expect, bodies) if expect is not None else None
        if not ok or (expect is not None and expected is None):
            return None
        return Task(label=str(label), scene=scene, layout=str(layout),
                    paraphrases=tuple(s[1:-1] for s in strings), forms=tuple(forms),
                    expect=expected, source=self.source(label),
                    paraphrase_sources=tuple(self.source(s) for s in strings))

    def test(self, item: Tree, scene: str, bodies: dict[str, Body],
             layouts: set[str]) -> ListedTest | None:
        level, name, layout, string, *rest = item.children
        ok = True
        test_id = f"{scene}/{level}/{name}"
        if test_id in self.tests:
            self.error("duplicate-test", f"test {name!s} of {level!s} is also defined at "
                                         f"{self.tests[test_id]}", name)
            ok = False
        self.tests.setdefault(test_id, self.source(name))
        if layout not in layouts:
            self.error("undefined-layout", f"no layout named {layout!s} in {scene}", layout)
            ok = False
        try:
            parse(string[1:-1])
        except InstructionError as error:
            self.error(f"instruction-{error.code}", error.message,
                       Source(file=self.file, line=string.line,
                              column=string.column + error.column), error.length)
            ok = False
        expected = self.expected(rest[0], bodies) if rest else None
        if not ok or (rest and expected is None):
            return None
        return ListedTest(name=str(name), scene=scene, level=str(level), layout=str(layout),
                          instruction=string[1:-1], expect=expected, source=self.source(name))

    def expected(self, node: Tree, bodies: dict[str, Body]) -> Expected | None:
        branch = None
        steps = []
        errors_before = len(self.errors)
        for child in node.children:
            if child.data == "branch":
                branch = str(child.children[0])
                continue
            arm, source, *rest = child.children
            if arm not in lf.Arm.__args__:
                self.error("bad-value", "the arm is 'left' or 'right'", arm)
            names = [source] + [t for t in rest if isinstance(t, Token) and t.type == "NAME"]
            waypoints = [w for w in rest if isinstance(w, Tree) and w.data == "waypoint"]
            names += [w.children[1] for w in waypoints]
            for token in names:
                if token not in bodies:
                    self.error("unknown-object", f"no object named {token!s}", token)
            relation = next((str(t.children[0]) for t in rest
                             if isinstance(t, Tree) and t.data == "relation"), None)
            yaw = next((float(t.children[0]) for t in rest
                        if isinstance(t, Tree) and t.data == "yaw"), None)
            target = str(rest[-1]) if child.data == "push" else (
                str(names[1]) if child.data == "place" else None)
            steps.append(dict(action=child.data, arm=str(arm), source=str(source),
                              relation=relation, target=target,
                              waypoints=tuple(sorted((str(w.children[0]), str(w.children[1]))
                                                     for w in waypoints)), yaw_degrees=yaw))
        if len(self.errors) > errors_before:
            return None
        return Expected(branch=branch, steps=tuple(Step(**s) for s in steps))

    def split(self, item: Tree, layouts: set[str]) -> SplitRule:
        level, *attribute_nodes = item.children
        found = self.attributes(attribute_nodes, ("layouts", "wordings", "max", "rounds", "seed"))
        values: dict = {"level": str(level)}
        for key in ("layouts", "wordings"):
            if key in found:
                node = found[key].children[1]
                names = node.children if node.data == "values" else [node]
                tokens = [n.children[0] for n in names if n.data == "name"]
                known = layouts if key == "layouts" else WORDINGS
                for token in tokens:
                    if token not in known:
                        code = "undefined-layout" if key == "layouts" else "unknown-wording"
                        self.error(code, f"unknown {key[:-1]} {token!s} (known: "
                                         f"{', '.join(sorted(known))})", token)
                values[key] = tuple(str(t) for t in tokens)
        for key, name in (("max", "max_tasks"), ("rounds", "rounds"), ("seed", "seed")):
            if key in found:
                number = self.number(found[key], 0 if key == "seed" else 1, 1e9)
                if number is not None:
                    values[name] = int(number)
        return SplitRule(**values)


def _expected(terminals) -> str:
    """Expected terminals as a reader knows them: '}' rather than RBRACE."""
    names = []
    for name in sorted(terminals):
        pattern = _parser().get_terminal(name).pattern
        names.append(repr(pattern.value) if pattern.type == "str" else name.lower())
    return f" (expected: {', '.join(sorted(names)[:12])})" if names else ""


def _coordinates(node: Tree) -> tuple[float, float]:
    return float(node.children[0]), float(node.children[1])


class _LayoutResolver:
    """Layouts written as placements or as operations on another layout -> absolute poses."""

    def __init__(self, loader: _Loader, bodies: dict[str, Body],
                 points: dict[str, tuple[float, float]], table: float,
                 jitter: dict[str, Jitter]):
        self.loader = loader
        self.jitter = jitter
        self.bodies = bodies
        self.points = points
        self.table = table
        self.raw: dict[str, Tree] = {}
        self.done: dict[str, dict[str, tuple] | None] = {}

    def resolve(self, nodes: list[Tree]) -> dict[str, Layout]:
        for node in nodes:
            name = node.children[0]
            if name in self.raw:
                self.loader.error("duplicate-layout", f"layout {name!s} is defined twice", name)
            self.raw[str(name)] = node
        layouts = {}
        for name, node in self.raw.items():
            arrangement = self.arrangement(name, ())
            if arrangement is None:
                continue
            placed = self.poses(arrangement, node.children[0])
            if placed is not None:
                base = node.children[1] if len(node.children) > 1 and isinstance(
                    node.children[1], Token) else None
                layouts[name] = Layout(name=name, base=str(base) if base else None, placed=placed)
        return layouts

    def known(self, token: Token) -> bool:
        if token not in self.bodies:
            self.loader.error("unknown-object", f"no object named {token!s}", token)
            return False
        return True

    def position(self, node) -> tuple[float, float] | None:
        if isinstance(node, Token):
            if node not in self.points:
                self.loader.error("unknown-point", f"no point named {node!s}", node)
                return None
            return self.points[str(node)]
        return _coordinates(node)

    def arrangement(self, name: str, chain: tuple[str, ...]) -> dict[str, tuple] | None:
        """body -> ("at", (x, y)) | ("on", body) | ("in", body), or None if it failed."""
        if name in self.done:
            return self.done[name]
        node = self.raw[name]
        if name in chain:
            self.loader.error("layout-cycle", "layouts derive from each other: "
                              + " -> ".join(chain[chain.index(name):] + (name,)),
                              node.children[0])
            self.done[name] = None
            return None
        rest = node.children[1:]
        arrangement: dict[str, tuple] = {}
        if rest and isinstance(rest[0], Token):
            base, rest = rest[0], rest[1:]
            if base not in self.raw:
                self.loader.error("undefined-layout", f"no layout named {base!s}", base)
                self.done[name] = None
                return None
            inherited = self.arrangement(str(base), chain + (name,))
            if inherited is None:
                self.done[name] = None
                return None
            arrangement = dict(inherited)
        errors_before = len(self.loader.errors)
        for op in rest:
            self.apply(op, arrangement)
        result = arrangement if len(self.loader.errors) == errors_before else None
        self.done[name] = result
        return result

    def apply(self, op: Tree, arrangement: dict[str, tuple]) -> None:
        kind, args = op.data, op.children
        if not all(self.known(t) for t in args if isinstance(t, Token) and not (
                kind in ("at", "move") and t is args[1])):
            return
        first = str(args[0])
        if kind in ("swap", "move", "remove", "put_on", "put_in") and first not in arrangement:
            self.loader.error("not-in-layout", f"{first} is not in this layout", args[0])
            return
        if kind == "at":
            position = self.position(args[1])
            if position is not None:
                arrangement[first] = ("at", position)
        elif kind == "move":
            position = self.position(args[1])
            if position is not None:
                arrangement[first] = ("at", position)
        elif kind in ("on", "put_on"):
            arrangement[first] = ("on", str(args[1]))
        elif kind in ("in_", "put_in"):
            if self.bodies[str(args[1])].kind != "bowl":
                self.loader.error("not-a-container", f"{args[1]!s} is not a bowl", args[1])
                return
            arrangement[first] = ("in", str(args[1]))
        elif kind == "swap":
            second = str(args[1])
            if first == second:
                self.loader.error("swap-self", f"swap names {first} twice", args[1])
            elif second not in arrangement:
                self.loader.error("not-in-layout", f"{second} is not in this layout", args[1])
            else:
                arrangement[first], arrangement[second] = arrangement[second], arrangement[first]
        elif kind == "remove":
            resting = [b for b, (how, where) in arrangement.items() if how != "at" and where == first]
            if resting:
                self.loader.error("support-removed", f"{', '.join(resting)} rests on {first}",
                                  args[0])
                return
            del arrangement[first]

    def poses(self, arrangement: dict[str, tuple], where: Token) -> dict[str, Placed] | None:
        placed: dict[str, Placed] = {}

        def pose(body: str, chain: tuple[str, ...]) -> Placed | None:
            if body in placed:
                return placed[body]
            how, value = arrangement[body]
            half = self.bodies[body].half_extents[2]
            if how == "at":
                result = Placed(x=value[0], y=value[1], z=self.table + half)
            elif value in chain or value == body:
                self.loader.error("support-cycle", f"{body} and {value} rest on each other", where)
                return None
            elif value not in arrangement:
                self.loader.error("not-in-layout", f"{body} rests on {value}, which is not in "
                                                   "this layout", where)
                return None
            else:
                support = pose(value, chain + (body,))
                if support is None:
                    return None
                bottom = support.z - self.bodies[value].half_extents[2]
                z = (support.z + self.bodies[value].half_extents[2] + half if how == "on"
                     else bottom + BOWL_FLOOR + half)
                result = Placed(x=support.x, y=support.y, z=z, support=value, relation=how)
            placed[body] = result
            return result

        for body in arrangement:
            if pose(body, ()) is None:
                return None
        self.check_overlaps(placed, where)
        return placed

    def check_overlaps(self, placed: dict[str, Placed], where: Token) -> None:
        """Bodies on the table stay on it and clear of each other with the jitter at its
        extremes; nothing is stacked on a body that rolls."""
        on_table = sorted(b for b, p in placed.items() if p.relation == "table")
        ranges = {b: self.jitter.get(b) or self.jitter.get("*") or Jitter() for b in on_table}
        low_x, high_x, low_y, high_y = table_bounds()
        for body in on_table:
            half, at, jitter = self.bodies[body].half_extents, placed[body], ranges[body]
            if (at.x + jitter.x[0] - half[0] < low_x or at.x + jitter.x[1] + half[0] > high_x
                    or at.y + jitter.y[0] - half[1] < low_y
                    or at.y + jitter.y[1] + half[1] > high_y):
                self.loader.error("off-table", f"{body} at ({at.x:g}, {at.y:g}) can leave the "
                                  f"table (x in [{low_x:g}, {high_x:g}], y in [{low_y:g}, "
                                  f"{high_y:g}]) in layout {where!s}", where)
        solid = [b for b in on_table if self.bodies[b].kind != "label"]
        for i, a in enumerate(solid):
            for b in solid[i + 1:]:
                pair = self.bodies[a], placed[a], self.bodies[b], placed[b]
                if _footprints_overlap(*pair, Jitter(), Jitter()):
                    self.loader.error("overlap", f"{a} and {b} overlap in layout {where!s}", where)
                elif _footprints_overlap(*pair, ranges[a], ranges[b]):
                    self.loader.error("overlap", f"{a} and {b} can overlap in layout {where!s} "
                                      "with the jitter at its extremes", where)
        for body, at in placed.items():
            if at.relation == "on" and self.bodies[at.support].kind == "sphere":
                self.loader.error("unstable-stack", f"{body} cannot rest on {at.support}, a "
                                  f"sphere, in layout {where!s}", where)


def _footprints_overlap(a: Body, pa: Placed, b: Body, pb: Placed, ja: Jitter,
                        jb: Jitter) -> bool:
    """Whether two footprints can overlap for some offsets within their jitter ranges."""
    dx = (pa.x - pb.x + ja.x[0] - jb.x[1], pa.x - pb.x + ja.x[1] - jb.x[0])
    dy = (pa.y - pb.y + ja.y[0] - jb.y[1], pa.y - pb.y + ja.y[1] - jb.y[0])
    gap_x = 0.0 if dx[0] <= 0 <= dx[1] else min(abs(dx[0]), abs(dx[1]))
    gap_y = 0.0 if dy[0] <= 0 <= dy[1] else min(abs(dy[0]), abs(dy[1]))
    round_kinds = ("sphere", "cylinder", "bowl")
    if a.kind in round_kinds and b.kind in round_kinds:
        return math.hypot(gap_x, gap_y) < a.half_extents[0] + b.half_extents[0]
    return (gap_x < a.half_extents[0] + b.half_extents[0]
            and gap_y < a.half_extents[1] + b.half_extents[1])
