"""Load .rf spec files into a validated Spec; report every problem at once.

Each problem is a SpecError with a code ('unknown-object', 'layout-cycle', ...) and the place it
was written; `load_spec` raises SpecErrors listing all of them. Loading goes on past a problem
without cascades: a body with a bad attribute is kept (with a stand-in value) so that later
uses of its name still resolve, and `load_partial` says which layouts hold such a body or did
not resolve, so that checks of the tasks on them (which would only repeat the problem) are
skipped while every other task is checked in the same run.

Every number is checked where it is written: finite and within the named limits of spec.py
(positions on the table, sizes, masses, friction, colours, jitter, the table's height, yaw,
rounds, caps and seeds), as are the counts of bodies, layouts and stacked bodies. Only regular
files are read (a FIFO or device named *.rf is refused unopened), and a symbolic link found in
a spec folder that points out of it is refused unfollowed. Nothing recurses on the depth of
what a spec writes (derived layouts, stacks).
"""

from __future__ import annotations

import hashlib
import math
import os
import stat
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path

from lark import Lark, Token, Tree, UnexpectedCharacters, UnexpectedEOF, UnexpectedToken

from robofollow.compiler import lf
from robofollow.compiler.behaviour import Step
from robofollow.compiler.observation import looks_alike
from robofollow.compiler.parser import parse
from robofollow.compiler.spec import (
    FRICTION_RANGE,
    HALF_EXTENT_RANGE,
    MASS_RANGE,
    MAX_BODIES,
    MAX_JITTER,
    MAX_LAYOUTS,
    MAX_ROUNDS,
    MAX_SEED,
    MAX_SPEC_BYTES,
    MAX_STACK,
    MAX_TASKS,
    RGB_RANGE,
    TABLE_HEIGHT_RANGE,
    YAW_RANGE,
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
_SETTING_RANGES = {"table_height": (TABLE_HEIGHT_RANGE, " m")}
_SPLIT_NUMBERS = {  # attribute -> (SplitRule field, range)
    "max": ("max_tasks", (1, MAX_TASKS)), "rounds": ("rounds", (1, MAX_ROUNDS)),
    "seed": ("seed", (0, MAX_SEED))}

# the lines of the spec files of the latest load (what errors found after loading show)
_LINES: dict[str, tuple[str, ...]] = {}


def _split_lines(text: str) -> list[str]:
    """Lines as the spec parser counts them: split at '\n' only (a '\r' before it dropped)."""
    return [line.removesuffix("\r") for line in text.split("\n")]


def _file_lines(file: str) -> tuple[str, ...]:
    if file in _LINES:
        return _LINES[file]
    try:
        if not stat.S_ISREG(os.stat(file).st_mode):
            return ()
        with open(file, "rb") as source:
            data = source.read(MAX_SPEC_BYTES)
    except OSError:
        return ()
    return tuple(_split_lines(data.decode("utf-8", errors="replace")))


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
    return [path for path, _ in _found(paths)]


def _found(paths: list[Path] | Path) -> list[tuple[Path, Path | None]]:
    """(file, the folder it was found in, or None when it was named itself), in a stable
    order. Finding opens nothing: what is found is checked before it is read."""
    files: list[tuple[Path, Path | None]] = []
    for path in [paths] if isinstance(paths, Path) else paths:
        if path.is_dir():
            files.extend((file, path) for file in sorted(path.rglob(f"*{SPEC_SUFFIX}")))
        else:
            files.append((path, None))
    return files


def _why_not_read(path: Path, folder: Path | None) -> str | None:
    """Why a spec file is not to be read (None: a regular file). A link found in a folder must
    stay inside it; its target is judged by its name and kind, never opened."""
    try:
        if folder is not None and path.is_symlink():
            target = Path(os.path.realpath(path))
            if not target.is_relative_to(Path(os.path.realpath(folder))):
                return (f"a symbolic link that leads out of the spec folder {folder}; it is not "
                        "followed (copy the file into the folder instead)")
        info = os.stat(path)
    except OSError as error:
        return f"cannot read it: {error.strerror or error}"
    if stat.S_ISDIR(info.st_mode):
        return "a folder, not a spec file"
    if not stat.S_ISREG(info.st_mode):
        return "not a regular file (a FIFO, socket or device); it is not read"
    if info.st_size > MAX_SPEC_BYTES:
        return (f"{info.st_size} bytes, more than a spec file may hold ({MAX_SPEC_BYTES} "
                "bytes)")
    return None


def _read(path: Path) -> bytes:
    """The bytes of a regular file; opened without blocking, and checked again once open (the
    file may have been replaced since it was looked at)."""
    descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    with os.fdopen(descriptor, "rb") as source:
        if not stat.S_ISREG(os.fstat(descriptor).st_mode):
            raise OSError(f"{path} is not a regular file")
        data = source.read(MAX_SPEC_BYTES + 1)
    if len(data) > MAX_SPEC_BYTES:
        raise OSError(f"more than a spec file may hold ({MAX_SPEC_BYTES} bytes)")
    return data


def not_utf8(data: bytes, error: UnicodeDecodeError) -> tuple[int, int, str, str]:
    """(line, column, the line as text, what is wrong) of the first byte that is not UTF-8
    (the column counts characters, as an editor does)."""
    start = error.start
    line_start = data.rfind(b"\n", 0, start) + 1
    line_end = data.find(b"\n", start)
    line = data.count(b"\n", 0, start) + 1
    column = len(data[line_start:start].decode("utf-8")) + 1
    shown = data[line_start:line_end if line_end >= 0 else len(data)].decode(
        "utf-8", errors="replace").removesuffix("\r")
    return line, column, shown, f"the file is not UTF-8 text: byte 0x{data[start]:02x} " \
                                f"({error.reason})"


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
    return _Loader().load(_found(paths))


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
    def load(self, files: list[tuple[Path, Path | None]]) -> Loaded:
        if not files:
            return Loaded(None, [SpecError("no-specs", "no .rf spec files found",
                                           file="<specs>", line=1, column=1)])
        digest = hashlib.sha256()
        scenes: dict[str, Scene] = {}
        _LINES.clear()  # (only the files of the latest load are kept)
        for path, folder in files:
            self.file = str(path)
            text = self.text(path, folder)
            if text is None:
                continue
            digest.update(path.name.encode() + b"\0" + text.encode() + b"\0")
            self.lines[self.file] = _split_lines(text)
            _LINES[self.file] = tuple(self.lines[self.file])
            tree = self.syntax(text)
            if tree is not None and not tree.children:
                self.error("empty-spec", "no scene in this file (a spec file holds one or more "
                           "scene NAME \"title\" { ... } blocks)",
                           Source(file=self.file, line=1, column=1))
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

    def text(self, path: Path, folder: Path | None) -> str | None:
        """The file's text, or None when it is not read (the reason is an error at 1:1, or at
        the first byte that is not UTF-8)."""
        why = _why_not_read(path, folder)
        data = None
        if why is None:
            try:
                data = _read(path)
            except OSError as error:
                why = f"cannot read it: {error.strerror or error}"
        if data is None:
            self.errors.append(SpecError("unreadable", why, file=self.file, line=1, column=1))
            return None
        try:
            return data.decode("utf-8")
        except UnicodeDecodeError as error:
            line, column, shown, message = not_utf8(data, error)
            self.errors.append(SpecError("encoding", message, file=self.file, line=line,
                                         column=column, source_line=shown))
            return None

    def syntax(self, text: str) -> Tree | None:
        try:
            return _parser().parse(text)
        except (UnexpectedEOF, UnexpectedToken) as error:
            if isinstance(error, UnexpectedEOF) or error.token.type == "$END":
                lines = _split_lines(text.rstrip())
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
        settings = dict(_SETTINGS)
        by_kind: dict[str, list[Tree]] = {}
        for item in items:
            by_kind.setdefault(item.data, []).append(item)
        points, bad_points = self.points(by_kind.get("point", []))
        seen_settings: set[str] = set()
        for item in by_kind.get("setting", []):
            self.setting(item, settings, seen_settings)
        body_nodes, layout_nodes = by_kind.get("body", []), by_kind.get("layout", [])
        bodies: dict[str, Body] = {}
        for item in body_nodes:
            body = self.body(item)
            if body.id in bodies:  # the first stands, and what uses the name is not checked
                self.error("duplicate-object", f"{body.id!r} is defined twice", item.children[1])
                self.broken.add(body.id)
                continue
            bodies[body.id] = body
        # beyond a count limit the scene's layouts are not resolved (nor its tasks checked)
        too_many = False
        for nodes, limit, what, at in ((body_nodes, MAX_BODIES, "bodies", 1),
                                       (layout_nodes, MAX_LAYOUTS, "layouts", 0)):
            if len(nodes) > limit:  # reported at the first one beyond the limit
                self.error(f"too-many-{what}", f"scene {name!s} declares {len(nodes)} {what}; "
                           f"at most {limit} are allowed", nodes[limit].children[at])
                too_many = True
        if not too_many:  # (pairwise: not for a scene beyond the limit)
            self.check_colours(bodies, body_nodes)
        jitter = self.jitters(by_kind.get("jitter", []), bodies)
        table = settings["table_height"]
        if too_many:
            layouts: dict[str, Layout] = {}
            defined = {str(item.children[0]) for item in layout_nodes}
        else:
            resolver = _LayoutResolver(self, bodies, points, bad_points, table, jitter)
            layouts = resolver.resolve(layout_nodes)
            defined = set(resolver.raw)  # a layout that failed to resolve is reported once, there
        if not by_kind.get("task"):
            self.error("no-tasks", f"scene {name!s} has no training tasks (write at least one "
                       "task NAME on LAYOUT { \"instruction\" ... })", name)
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

    def points(self, items: list[Tree]) -> tuple[dict[str, tuple[float, float]], set[str]]:
        """The named points, and those whose coordinates are bad (reported here, once: a layout
        that uses one fails without a second report)."""
        points: dict[str, tuple[float, float]] = {}
        bad: set[str] = set()
        for item in items:
            point, coordinates = item.children
            if point in points or point in bad:
                self.error("duplicate-point", f"point {point!s} is defined twice", point)
                continue
            position = self.coordinates(coordinates, f"point {point!s}")
            if position is None:
                bad.add(str(point))
            else:
                points[str(point)] = position
        return points, bad

    def coordinates(self, node: Tree, what: str) -> tuple[float, float] | None:
        """(x, y) as written, or None (reported at the number) when a coordinate is not finite
        or the position is not on the table top."""
        tokens = node.children
        values = [float(token) for token in tokens]
        for token, value, axis in zip(tokens, values, "xy", strict=True):
            if not math.isfinite(value):
                self.error("bad-value", f"{what}: {axis} = {_shown(token)} is not a finite "
                           "number", token)
                return None
        low_x, high_x, low_y, high_y = table_bounds()
        for token, value, low, high in zip(tokens, values, (low_x, low_y), (high_x, high_y),
                                           strict=True):
            if not low <= value <= high:
                self.error("off-table", f"{what} at ({values[0]:g}, {values[1]:g}) can leave "
                           f"the table: it is beyond the table top (x in [{low_x:g}, "
                           f"{high_x:g}], y in [{low_y:g}, {high_y:g}])", token)
                return None
        return values[0], values[1]

    def check_colours(self, bodies: dict[str, Body], items: list[Tree]) -> None:
        """Bodies that look the same (kind, size, rgb) must not be told apart by colour words
        a camera cannot see."""
        tokens = {str(item.children[1]): item.children[1] for item in items}
        seen: list[Body] = []
        for body in bodies.values():
            if body.id in self.broken:
                continue
            twin = next((b for b in seen if looks_alike(b, body) and b.color != body.color), None)
            if twin is not None:
                self.error("colour-mismatch", f"{body.id} looks the same as {twin.id} (kind, "
                           f"size, rgb) but is called {body.color}, not {twin.color}",
                           tokens[body.id])
            seen.append(body)

    def setting(self, item: Tree, settings: dict[str, float], seen: set[str]) -> None:
        name, value = item.children
        if name not in settings:
            self.error("unknown-setting", f"unknown setting {name!s} (known: "
                                          f"{', '.join(sorted(settings))})", name)
            return
        if name in seen:
            self.error("duplicate-setting", f"{name!s} is set twice", name)
            return
        seen.add(str(name))
        if value.data != "number":
            self.error("bad-value", f"{name!s} takes a number", name)
            return
        bounds, unit = _SETTING_RANGES[str(name)]
        number = self.checked(value.children[0], str(name), bounds, unit)
        if number is not None:
            settings[str(name)] = number

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

    def checked(self, token: Token, what: str, bounds: tuple[float, float], unit: str = "",
                whole: bool = False) -> float | None:
        """The number written at `token`, or None (reported there) when it is not finite,
        not within `bounds` or, for a count, not a whole number."""
        value, (low, high) = float(token), bounds
        if not math.isfinite(value):
            self.error("bad-value", f"{what} = {_shown(token)} is not a finite number; it must "
                       f"be in [{low:g}, {high:g}]{unit}", token)
        elif not low <= value <= high:
            self.error("bad-value", f"{what} = {_shown(token)} is out of range: it must be in "
                       f"[{low:g}, {high:g}]{unit}", token)
        elif whole and value != int(value):
            self.error("bad-value", f"{what} = {_shown(token)} must be a whole number", token)
        else:
            return value
        return None

    def number(self, node: Tree, bounds: tuple[float, float], unit: str = "",
               whole: bool = False) -> float | None:
        """An attribute that takes one number (checked as `checked` does)."""
        key, value = node.children
        if value.data != "number":
            self.error("bad-value", f"{key!s} takes a number", key)
            return None
        return self.checked(value.children[0], str(key), bounds, unit, whole)

    def numbers(self, node: Tree, count: int, bounds: tuple[float, float],
                unit: str = "") -> tuple[float, ...] | None:
        """An attribute that takes `count` numbers: (a, b, c)."""
        key, value = node.children
        items = value.children if value.data == "values" else [value]
        if len(items) != count or any(i.data != "number" for i in items):
            self.error("bad-value", f"{key!s} takes {count} numbers in [{bounds[0]:g}, "
                       f"{bounds[1]:g}]{unit}: ({', '.join(['n'] * count)})", key)
            return None
        numbers = [self.checked(i.children[0], str(key), bounds, unit) for i in items]
        return None if None in numbers else tuple(numbers)

    def body(self, item: Tree) -> Body:
        """The body as written; a bad or missing attribute is an error, and the body is kept
        with a stand-in value and marked broken (the checks of what rests on a stand-in would
        only repeat the error)."""
        kind_node, name, kind, *attribute_nodes = item.children
        fixture = kind_node.children[0] == "fixture"
        known = kind in _SIZES
        if not known:
            self.error("unknown-kind", f"unknown kind {kind!s} (expected one of: "
                                       f"{', '.join(_SIZES)})", kind)
            self.broken.add(str(name))
        sizes = _SIZES[str(kind)] if known else tuple(dict.fromkeys(
            a for names in _SIZES.values() for a in names))
        allowed = sizes + _COMMON + (() if fixture else _PHYSICS)
        found = self.attributes(attribute_nodes, allowed)
        missing = [a for a in allowed if a not in found and (known or a not in sizes)]
        if missing:
            self.error("missing-attribute", f"{name!s} needs {', '.join(missing)}", name)
        color = found["color"].children[1] if "color" in found else None
        if color is not None and (color.data != "name"
                                  or color.children[0] not in lf.Color.__args__):
            where = color.children[0] if color.data == "name" else found["color"].children[0]
            self.error("bad-value", f"color must be one of {', '.join(lf.Color.__args__)}", where)
            color = None
        rgb = self.numbers(found["rgb"], 3, RGB_RANGE) if "rgb" in found else None
        half = self.size(str(kind), found) if known else None
        physics = {key: self.number(found[key], bounds, unit) for key, (bounds, unit) in
                   (("mass", (MASS_RANGE, " kg")), ("friction", (FRICTION_RANGE, "")))
                   if key in found}
        if color is None or half is None or rgb is None or None in physics.values():
            self.broken.add(str(name))
        return Body(id=str(name), kind=str(kind) if known else "cube", fixture=fixture,
                    color=str(color.children[0]) if color is not None else "red",
                    rgb=rgb or (0.5, 0.5, 0.5), half_extents=half or (0.02, 0.02, 0.02),
                    **{key: value for key, value in physics.items() if value is not None})

    def size(self, kind: str, found: dict[str, Tree]) -> tuple[float, float, float] | None:
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

    def jitters(self, items: list[Tree], bodies: dict[str, Body]) -> dict[str, Jitter]:
        """Jitter by body ('*': the default). A bad range is reported once: it stands as no
        jitter, and the bodies it applies to are marked broken."""
        jitter: dict[str, Jitter] = {}
        bad: set[str] = set()
        for item in items:
            target, attributes = item.children[0], item.children[1:]
            if target in jitter or target in bad:
                self.error("duplicate-jitter", f"the jitter of {target!s} is given twice",
                           target)
                continue
            if target != "*" and target not in bodies:
                self.error("unknown-object", f"no object named {target!s}", target)
            ranges = self.jitter(attributes)
            if ranges is None:
                bad.add(str(target))
            jitter[str(target)] = ranges or Jitter()
        for body in bodies:
            if body in bad or (body not in jitter and "*" in bad):
                self.broken.add(body)
        return jitter

    def jitter(self, attributes: list[Tree]) -> Jitter | None:
        found = self.attributes(attributes, ("x", "y"))
        ranges = {}
        ok = True
        for axis, node in found.items():
            value = node.children[1]
            if value.data != "interval":
                self.error("bad-value", f"{axis} takes an interval [low, high] (m)",
                           node.children[0])
                ok = False
                continue
            low, high = (self.checked(t, f"jitter {axis}", (-MAX_JITTER, MAX_JITTER), " m")
                         for t in value.children)
            if low is None or high is None:
                ok = False
            elif low > high:
                self.error("bad-value", f"{axis} takes an interval [low, high] with low <= high",
                           node.children[0])
                ok = False
            else:
                ranges[axis] = (low, high)
        return Jitter(**ranges) if ok else None

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
            yaw_node = next((t for t in rest if isinstance(t, Tree) and t.data == "yaw"), None)
            yaw = None if yaw_node is None else self.checked(yaw_node.children[0], "yaw",
                                                             YAW_RANGE, " degrees")
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
                if any(n.data != "name" for n in names):
                    self.error("bad-value", f"{key} takes names: {key}=(a, b, ...)",
                               found[key].children[0])
                    continue
                tokens = [n.children[0] for n in names]
                known = layouts if key == "layouts" else WORDINGS
                for token in tokens:
                    if token not in known:
                        code = "undefined-layout" if key == "layouts" else "unknown-wording"
                        self.error(code, f"unknown {key[:-1]} {token!s} (known: "
                                         f"{', '.join(sorted(known))})", token)
                values[key] = tuple(str(t) for t in tokens)
        for key, (name, bounds) in _SPLIT_NUMBERS.items():
            if key in found:
                number = self.number(found[key], bounds, whole=True)
                if number is not None:
                    values[name] = int(number)
        return SplitRule(**values)


def _shown(token: Token) -> str:
    """A number as written, shortened when it is long (as an overflow to infinity is)."""
    return str(token) if len(token) <= 24 else f"{token[:12]}...{token[-6:]} ({len(token)} " \
                                                "characters)"


def _expected(terminals) -> str:
    """Expected terminals as a reader knows them: '}' rather than RBRACE."""
    names = []
    for name in sorted(terminals):
        pattern = _parser().get_terminal(name).pattern
        names.append(repr(pattern.value) if pattern.type == "str" else name.lower())
    return f" (expected: {', '.join(sorted(names)[:12])})" if names else ""


class _LayoutResolver:
    """Layouts written as placements or as operations on another layout -> absolute poses.
    Iterative throughout: neither a long chain of derived layouts nor a stack recurses."""

    def __init__(self, loader: _Loader, bodies: dict[str, Body],
                 points: dict[str, tuple[float, float]], bad_points: set[str], table: float,
                 jitter: dict[str, Jitter]):
        self.loader = loader
        self.jitter = jitter
        self.bodies = bodies
        self.points = points
        self.bad_points = bad_points
        self.table = table
        self.raw: dict[str, Tree] = {}
        self.done: dict[str, dict[str, tuple] | None] = {}
        self.reported: set[tuple] = set()  # geometry problems already reported (once each)
        self.unposed: set[str] = set()  # layouts whose bodies could not be posed

    def resolve(self, nodes: list[Tree]) -> dict[str, Layout]:
        for node in nodes:
            name = node.children[0]
            if name in self.raw:
                self.loader.error("duplicate-layout", f"layout {name!s} is defined twice", name)
            self.raw[str(name)] = node
        for name in self.raw:
            self.arrangement(name)
        posed: dict[str, Layout] = {}
        for name in self.raw:
            chain = []  # the layout and its bases not yet posed, posed bases first
            current = name
            while current is not None and current not in posed and current not in self.unposed \
                    and self.done.get(current) is not None:
                chain.append(current)
                current = self.base(current)
            for layout in reversed(chain):
                base = self.base(layout)
                # derived from a layout that could not be posed: fails quietly if it also fails
                placed = self.poses(self.done[layout], self.raw[layout].children[0],
                                    quiet=base in self.unposed)
                if placed is None:
                    self.unposed.add(layout)
                else:
                    posed[layout] = Layout(name=layout, base=base, placed=placed)
        return {name: posed[name] for name in self.raw if name in posed}

    def base(self, name: str) -> str | None:
        rest = self.raw[name].children[1:]
        return str(rest[0]) if rest and isinstance(rest[0], Token) else None

    def known(self, token: Token) -> bool:
        if token not in self.bodies:
            self.loader.error("unknown-object", f"no object named {token!s}", token)
            return False
        return True

    def position(self, node, body: str) -> tuple[float, float] | None:
        if isinstance(node, Token):
            if node in self.bad_points:  # already reported where the point is defined
                return None
            if node not in self.points:
                self.loader.error("unknown-point", f"no point named {node!s}", node)
                return None
            return self.points[str(node)]
        return self.loader.coordinates(node, body)

    def arrangement(self, name: str) -> dict[str, tuple] | None:
        """body -> ("at", (x, y)) | ("on", body) | ("in", body), or None if it failed. The chain
        of bases is followed down to a resolved layout (or a cycle, or an undefined base), then
        resolved back up in a loop."""
        chain: list[str] = []
        current = name
        while current not in self.done:
            if current in chain:
                cycle = chain[chain.index(current):] + [current]
                self.loader.error("layout-cycle", "layouts derive from each other: "
                                  + " -> ".join(cycle), self.raw[current].children[0])
                return self.fail(chain)
            chain.append(current)
            rest = self.raw[current].children[1:]
            if not (rest and isinstance(rest[0], Token)):
                break  # written as placements
            if rest[0] not in self.raw:
                self.loader.error("undefined-layout", f"no layout named {rest[0]!s}", rest[0])
                return self.fail(chain)
            current = str(rest[0])
        for layout in reversed(chain):
            rest = self.raw[layout].children[1:]
            arrangement: dict[str, tuple] = {}
            if rest and isinstance(rest[0], Token):
                inherited = self.done[str(rest[0])]
                if inherited is None:
                    return self.fail(chain)
                arrangement, rest = dict(inherited), rest[1:]
            applied = [self.apply(op, arrangement) for op in rest]  # every op, every error
            self.done[layout] = arrangement if all(applied) else None
        return self.done[name]

    def fail(self, chain: list[str]) -> None:
        for layout in chain:
            self.done.setdefault(layout, None)
        return None

    def apply(self, op: Tree, arrangement: dict[str, tuple]) -> bool:
        """Apply one operation; False (reported, or already reported) when it fails."""
        kind, args = op.data, op.children
        if not all(self.known(t) for t in args if isinstance(t, Token) and not (
                kind in ("at", "move") and t is args[1])):
            return False
        first = str(args[0])
        if kind in ("swap", "move", "remove", "put_on", "put_in") and first not in arrangement:
            self.loader.error("not-in-layout", f"{first} is not in this layout", args[0])
            return False
        if kind in ("at", "move"):
            position = self.position(args[1], first)
            if position is None:
                return False
            arrangement[first] = ("at", position)
        elif kind in ("on", "put_on"):
            arrangement[first] = ("on", str(args[1]))
        elif kind in ("in_", "put_in"):
            if self.bodies[str(args[1])].kind != "bowl":
                self.loader.error("not-a-container", f"{args[1]!s} is not a bowl", args[1])
                return False
            arrangement[first] = ("in", str(args[1]))
        elif kind == "swap":
            second = str(args[1])
            if first == second:
                self.loader.error("swap-self", f"swap names {first} twice", args[1])
                return False
            if second not in arrangement:
                self.loader.error("not-in-layout", f"{second} is not in this layout", args[1])
                return False
            arrangement[first], arrangement[second] = arrangement[second], arrangement[first]
        elif kind == "remove":
            resting = [b for b, (how, where) in arrangement.items() if how != "at" and where == first]
            if resting:
                self.loader.error("support-removed", f"{', '.join(resting)} rests on {first}",
                                  args[0])
                return False
            del arrangement[first]
        return True

    def poses(self, arrangement: dict[str, tuple], where: Token,
              quiet: bool = False) -> dict[str, Placed] | None:
        """Every body's pose: a stack is walked down to the body on the table, then placed
        upwards (a loop; at most MAX_STACK bodies high)."""
        placed: dict[str, Placed] = {}
        report = (lambda *_: None) if quiet else self.report
        height: dict[str, int] = {}  # bodies from this one down to the table, itself included
        for start in arrangement:
            stack = [start]
            while stack[-1] not in placed:
                body = stack[-1]
                how, value = arrangement[body]
                if how == "at":
                    break
                if value in stack:
                    report(("support-cycle", body, value), "support-cycle",
                           f"{body} rests on itself" if value == body else
                           f"{body} and {value} rest on each other", where)
                    return None
                if value not in arrangement:
                    report(("not-in-layout", body, value), "not-in-layout",
                           f"{body} rests on {value}, which is not in this layout", where)
                    return None
                stack.append(value)
            for body in reversed(stack):
                if body in placed:
                    continue
                how, value = arrangement[body]
                half = self.bodies[body].half_extents[2]
                if how == "at":
                    placed[body], height[body] = Placed(x=value[0], y=value[1],
                                                        z=self.table + half), 1
                    continue
                height[body] = height[value] + 1
                if height[body] > MAX_STACK:
                    report(("stack-too-tall", body), "stack-too-tall", f"{body} rests on a "
                           f"stack of {height[value]} bodies in layout {where!s}; at most "
                           f"{MAX_STACK} bodies may rest on one another", where)
                    return None
                support = placed[value]
                bottom = support.z - self.bodies[value].half_extents[2]
                z = (support.z + self.bodies[value].half_extents[2] + half if how == "on"
                     else bottom + BOWL_FLOOR + half)
                placed[body] = Placed(x=support.x, y=support.y, z=z, support=value, relation=how)
        self.check_overlaps(placed, where)
        return placed  # in the order the recursive walk placed them: supports first

    def report(self, key: tuple, code: str, message: str, where: Token) -> None:
        """A problem of poses, reported at the first layout that has it (a derived layout
        that keeps it does not repeat it, and fails, or is checked, without a second report)."""
        if key not in self.reported:
            self.reported.add(key)
            self.loader.error(code, message, where)

    def check_overlaps(self, placed: dict[str, Placed], where: Token) -> None:
        """Bodies on the table stay on it and clear of each other with the jitter at its
        extremes; nothing is stacked on a body that rolls. A broken body (a bad attribute,
        reported there) is left out."""
        broken = self.loader.broken
        on_table = sorted(b for b, p in placed.items() if p.relation == "table" and b not in broken)
        ranges = {b: self.jitter.get(b) or self.jitter.get("*") or Jitter() for b in on_table}
        low_x, high_x, low_y, high_y = table_bounds()
        for body in on_table:
            half, at, jitter = self.bodies[body].half_extents, placed[body], ranges[body]
            if (at.x + jitter.x[0] - half[0] < low_x or at.x + jitter.x[1] + half[0] > high_x
                    or at.y + jitter.y[0] - half[1] < low_y
                    or at.y + jitter.y[1] + half[1] > high_y):
                self.report(("off-table", body, at.x, at.y), "off-table",
                            f"{body} at ({at.x:g}, {at.y:g}) can leave the table (x in "
                            f"[{low_x:g}, {high_x:g}], y in [{low_y:g}, {high_y:g}]) in layout "
                            f"{where!s}", where)
        solid = [b for b in on_table if self.bodies[b].kind != "label"]
        for i, a in enumerate(solid):
            for b in solid[i + 1:]:
                pair = self.bodies[a], placed[a], self.bodies[b], placed[b]
                key = ("overlap", a, placed[a].x, placed[a].y, b, placed[b].x, placed[b].y)
                if _footprints_overlap(*pair, Jitter(), Jitter()):
                    self.report(key, "overlap", f"{a} and {b} overlap in layout {where!s}", where)
                elif _footprints_overlap(*pair, ranges[a], ranges[b]):
                    self.report(key, "overlap", f"{a} and {b} can overlap in layout {where!s} "
                                "with the jitter at its extremes", where)
        for body, at in placed.items():
            if at.relation == "on" and self.bodies[at.support].kind == "sphere" and not (
                    {body, at.support} & broken):
                self.report(("unstable-stack", body, at.support), "unstable-stack",
                            f"{body} cannot rest on {at.support}, a sphere, in layout "
                            f"{where!s}", where)


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
