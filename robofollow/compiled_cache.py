"""The compiled benchmark as `compile` writes it and an env, `eval`, `serve`, `generate`, `vqa`,
`expert`, `score` and `render` read it, cached on disk per spec file, so that they start
without compiling the specs (seconds) and an edited spec compiles only its own scenes.

They need the spec (its scenes), each scene's training behaviours ('did instead') and the
episode records; `compile` also the splits, the audit and the build's files. A scene's splits
and its part of the audit depend on its own spec alone, so each .rf file is compiled by itself
and kept in one JSON Lines file, `<cache>/compiled/<path>-<spec>-<code>.jsonl` (16 hex digits
of the sha256 of the file's path, of its bytes and of `code_digest`): a header (format, key,
episode ids, the sha256 of the rest), the file's scenes and their training behaviours, one
episode per line as the build writes `episodes/*.jsonl`, then one line of what only `build`
reads (the file's audit, its test tasks, its other build files); an episode is parsed when
asked for. The key is a sha256 over the code digest (FORMAT,
RoboFollow's version, the compiler's code and grammars: SOURCES), the file's path and its
bytes, so a change to any of them compiles that file again. A file is written to a temporary
name and renamed into place; one that does not verify (corrupt, truncated, stale) is compiled
again and replaced. A load that compiles says so on stderr, naming the scenes and why.

Specs that only load together are compiled together, uncached: an unreadable file, a link in
the folder, a scene or task label defined in two files, a spec with errors (they are reported
for every file at once). `<cache>` is resources.cache_root(); ROBOFOLLOW_NO_CACHE=1 turns the
disk cache off (each process then compiles once).
"""

from __future__ import annotations

import hashlib
import json
import os
import secrets
import sys
import warnings
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import cache, cached_property, lru_cache
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING

from robofollow.benchmark.episode import Episode
from robofollow.compiler.authoring.spec_files import spec_files
from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.compiler.scene.spec import (
    LEVELS,
    MAX_SPEC_BYTES,
    Scene,
    Spec,
    scene_behaviours,
)
from robofollow.files import read_file_at_most
from robofollow.resources import cache_root

if TYPE_CHECKING:
    from robofollow.benchmark.compiled import Compiled

FORMAT = 3  # bump when the file layout or the records' meaning changes
KEEP = 64  # cache files kept (the newest); older ones are removed when one is written
# the code the compile runs, under robofollow/ (a test checks that these are the modules the
# cached compile imports, and beside them only the rest of the compiler): a change to it, and
# only to it, compiles again
SOURCES = ("benchmark/__init__.py", "benchmark/compiled.py", "benchmark/episode.py",
           "benchmark/episode_hash.py",
           "benchmark/guessing.py", "benchmark/labels.py", "benchmark/output.py",
           "benchmark/pipeline.py", "benchmark/render.py", "benchmark/rounds.py",
           "benchmark/summary.py", "compiled_cache.py", "errors.py",
           "resources.py", "files.py", "oracle/__init__.py", "oracle/chance.py", "compiler",
           "audit")


@dataclass(frozen=True)
class FilePart:
    """What one spec file compiles to: its scenes, their training behaviours by label, their
    episodes (ids, and records as JSON lines), and what only `build` reads, as JSON: the
    file's audit, its test tasks and its other build files (`render.task_files`). A part
    compiled in this process also holds the compile and its `render.rendered` files, which
    `build` takes as they are."""

    scenes: dict[str, Scene]
    training: dict[str, Behaviour]
    ids: tuple[str, ...]
    lines: tuple[bytes, ...]
    build: bytes
    made: tuple[Compiled, dict[str, str]] | None = None  # (the compile, its rendered files)


@dataclass(frozen=True)
class Episodes:
    """The spec, the training behaviours and every episode (in `benchmark.rounds.all_episodes`
    order), each parsed when asked for (a fresh object every time); `release` names the frozen
    release they were read from, with its digest (None: a working compile of specs)."""

    spec: Spec
    training: dict[str, Behaviour]
    ids: tuple[str, ...]
    lines: tuple[bytes, ...]
    release: str | None = None
    release_digest: str | None = None

    @cached_property
    def index(self) -> dict[str, int]:
        return {episode: i for i, episode in enumerate(self.ids)}

    def record(self, episode_id: str) -> Episode:
        """The episode with this id (`<scene>/<level>/<task>#r<round>`)."""
        if episode_id not in self.index:
            raise _unknown(episode_id, self.task_ids)
        return Episode.model_validate_json(self.lines[self.index[episode_id]])

    @cached_property
    def task_ids(self) -> tuple[str, ...]:
        """Every test task's id, in episode order."""
        return tuple(dict.fromkeys(episode.partition("#")[0] for episode in self.ids))

    def episodes(self, keep: Callable[[str], bool] = lambda episode_id: True) -> list[Episode]:
        """The episodes whose ids `keep` accepts, in order, each parsed afresh (only those)."""
        return [Episode.model_validate_json(line)
                for episode, line in zip(self.ids, self.lines) if keep(episode)]

    def candidates(self, scene: str) -> dict[str, Behaviour]:
        """The scene's training behaviours by label (as `Compiled.candidates`)."""
        return scene_behaviours(self.spec, self.training, scene)

    def select(self, scene: str | None = None, level: str | None = None) -> tuple[str, ...]:
        """The ids of the episodes of a scene and a level (None: any)."""
        chosen = tuple(episode for episode in self.ids
                       if scene in (None, episode.split("/", 1)[0])
                       and level in (None, episode.split("/", 2)[1]))
        if not chosen:
            raise ValueError(f"no episodes of scene {scene!r} at level {level!r} (scenes: "
                             f"{', '.join(self.spec.scenes)}; levels: {', '.join(LEVELS)})")
        return chosen


def _unknown(episode_id: str, task_ids: tuple[str, ...]) -> Exception:
    from robofollow.benchmark.rounds import (
        unknown_episode,  # (imports the compiler: only on error)
    )

    return unknown_episode(episode_id, list(task_ids))


def cache_dir() -> Path | None:
    """Where compiled benchmarks are kept; None when ROBOFOLLOW_NO_CACHE turns the cache off."""
    root = cache_root()
    return root / "compiled" if root else None


def code_files() -> list[Path]:
    """The compile's code, templates and grammars."""
    package = Path(__file__).resolve().parent
    grammars = package / "grammar" if (package / "grammar").is_dir() else package.parent / "grammar"
    files = sorted(grammars.glob("*.lark"))
    for source in map(package.joinpath, SOURCES):
        found = source.rglob("*") if source.is_dir() else [source]
        files += sorted(path for path in found if path.suffix in (".py", ".j2"))
    return files


@cache
def code_digest() -> str:
    """A sha256 over FORMAT, RoboFollow's version and `code_files` (once per process)."""
    digest = hashlib.sha256(f"{FORMAT}\0{_version()}\0".encode())
    for path in code_files():
        digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def _version() -> str:
    try:
        return metadata.version("robofollow")
    except metadata.PackageNotFoundError:
        return "unknown"


def _sha(data: str | bytes) -> str:
    return hashlib.sha256(data.encode() if isinstance(data, str) else data).hexdigest()


@dataclass(frozen=True)
class Entry:
    """A spec file as it is now: its path, bytes and cache key."""

    file: Path
    data: bytes

    @cached_property
    def key(self) -> str:
        return _sha(f"{code_digest()}\0{self.file}\0".encode() + self.data)

    @property
    def name(self) -> str:
        """The cache file's name: path, spec and code (see the module docstring)."""
        return f"{self.stem}-{_sha(self.data)[:16]}-{code_digest()[:16]}.jsonl"

    @property
    def stem(self) -> str:
        return _sha(str(self.file))[:16]


def load(specs: Path) -> Episodes:
    """The compiled benchmark of `specs` (a folder or a file): each spec file's part from the
    cache when it holds it, else compiled (and cached). Raises SpecErrors on bad specs; a cache
    that cannot be read or written is only passed over."""
    found = _found(specs)
    if found is None:
        return _whole(specs)
    spec, parts = found
    return Episodes(spec, _training(parts), tuple(i for part in parts for i in part.ids),
                    tuple(line for part in parts for line in part.lines))


def build(specs: Path) -> tuple[Compiled, dict[str, str]]:
    """What `robofollow compile` writes, from the same parts as `load`: the compiled benchmark
    of `specs` (a `compiled.Compiled`, as one compile of the whole folder gives it) and its
    `render.rendered` files. Raises SpecErrors on bad specs."""
    from pydantic import TypeAdapter

    from robofollow.benchmark.compiled import Part, assemble
    from robofollow.benchmark.output import REJECTED, episode_files, joined
    from robofollow.compiler.splits.tasks import Rejection, Splits, TestTask

    found = _found(specs)
    if found is None:
        return _build_whole(specs)
    spec, parts = found
    tasks, rejections = TypeAdapter(list[TestTask]), TypeAdapter(list[Rejection])
    pieces, files = [], []
    for part in parts:
        if part.made is not None:
            compiled, rendered = part.made
            pieces.append(Part(compiled.splits, compiled.report))
            files.append(rendered)
            continue
        content = json.loads(part.build)
        rejected = content["files"][REJECTED].splitlines()
        splits = Splits(tasks=tuple(tasks.validate_python(content["tasks"])),
                        rejected=tuple(rejections.validate_json(f"[{','.join(rejected)}]")))
        pieces.append(Part(splits, content["report"]))
        files.append(episode_files(part.scenes, part.ids, part.lines) | content["files"])
    return assemble(spec, _training(parts), pieces), joined(files)


def _training(parts: tuple[FilePart, ...]) -> dict[str, Behaviour]:
    """The parts' training behaviours by label, in file order."""
    return {label: b for part in parts for label, b in part.training.items()}


def _build_whole(specs: Path) -> tuple[Compiled, dict[str, str]]:
    """`build` of the specs compiled together, uncached."""
    from robofollow.benchmark.pipeline import compile_specs
    from robofollow.benchmark.render import rendered

    compiled = compile_specs(specs)
    return compiled, rendered(compiled)


def _found(specs: Path) -> tuple[Spec, tuple[FilePart, ...]] | None:
    """The spec of `specs` and each spec file's part, from the cache or compiled; None when
    the files must be compiled together (see the module docstring)."""
    specs = Path(os.path.realpath(specs))
    files = spec_files(specs)
    if not files or any(file.is_symlink() for file in files):
        return None
    read = [read_file_at_most(file, MAX_SPEC_BYTES)[0] for file in files]
    if any(data is None for data in read):  # not a readable regular file: the compile says so
        return None
    return _assemble(tuple(map(Entry, files, read)), cache_dir())


@lru_cache(maxsize=4)
def _assemble(entries: tuple[Entry, ...], folder: Path | None
              ) -> tuple[Spec, tuple[FilePart, ...]] | None:
    """The parts put together (one read or compile per specs state and cache folder, per
    process): the spec as one compile of the whole folder gives it, and the parts."""
    parts, compiled, cached = [], [], 0
    for entry in entries:
        part, why = _part(entry, folder)
        if part is None:
            return None
        parts.append(part)
        if why:
            compiled.append(f"{', '.join(part.scenes)} ({why})")
        else:
            cached += len(part.scenes)
    scenes = [scene for part in parts for scene in part.scenes]
    labels = [label for part in parts for label in part.training]
    if len(set(scenes)) != len(scenes) or len(set(labels)) != len(labels):
        return None  # (the compile reports what is defined twice)
    if compiled:
        tail = f", {cached} scene{'' if cached == 1 else 's'} from cache" if cached else ""
        print(f"compiled {', '.join(compiled)}{tail}", file=sys.stderr)
    digest = hashlib.sha256()
    for entry in entries:  # as the spec loader's digest: each file's name and text
        digest.update(entry.file.name.encode() + b"\0" + entry.data + b"\0")
    spec = Spec(scenes={s: scene for part in parts for s, scene in part.scenes.items()},
                digest=digest.hexdigest())
    return spec, tuple(parts)


def _part(entry: Entry, folder: Path | None) -> tuple[FilePart | None, str | None]:
    """One spec file's part and why it was compiled (None: read from the cache); no part when
    the file does not compile alone."""
    path = folder / entry.name if folder else None
    if path is not None:
        try:
            return _parse(path.read_bytes(), entry.key), None
        except (OSError, ValueError, KeyError, TypeError):  # missing, corrupt, stale
            why = _why(folder, entry)
    else:
        why = "caching is off"
    made = _compile(entry)
    if made is None:
        return None, None
    data, compiled, files = made
    if path is not None:
        _store(path, data)
    return replace(_parse(data, entry.key), made=(compiled, files)), why


def _why(folder: Path, entry: Entry) -> str:
    """Why a file is not in the cache: its spec or the code changed since it was cached, or
    it never was."""
    try:
        names = [name for name in os.listdir(folder) if name.startswith(entry.stem + "-")]
    except OSError:
        names = []
    spec = f"{entry.stem}-{_sha(entry.data)[:16]}-"
    if any(name.startswith(spec) for name in names):
        return "code changed"
    return "spec changed" if names else "not cached"


def _compile(entry: Entry) -> tuple[bytes, Compiled, dict[str, str]] | None:
    """One spec file compiled alone: its cache file's bytes, the compile and its rendered
    files; None when it has errors."""
    from robofollow.benchmark.output import episode_files
    from robofollow.benchmark.pipeline import compile_specs  # (seconds: only on a miss)
    from robofollow.benchmark.render import episodes, task_files
    from robofollow.errors import SpecErrors

    try:
        compiled = compile_specs([entry.file])
    except SpecErrors:
        return None
    ids, lines = episodes(compiled)
    files = task_files(compiled)
    head = {"scenes": {s: scene.model_dump(mode="json")
                       for s, scene in compiled.spec.scenes.items()},
            "training": {label: b.model_dump(mode="json")
                         for label, b in compiled.training.items()}}
    build = {"report": compiled.report,
             "tasks": [task.model_dump(mode="json") for task in compiled.splits.tasks],
             "files": files}
    body = (json.dumps(head).encode() + b"\n" + b"".join(line + b"\n" for line in lines)
            + json.dumps(build).encode() + b"\n")
    header = {"format": FORMAT, "key": entry.key, "sha256": _sha(body), "ids": ids}
    return (json.dumps(header).encode() + b"\n" + body, compiled,
            episode_files(compiled.spec.scenes, ids, lines) | files)


def _parse(data: bytes, key: str) -> FilePart:
    """The FilePart of a cache file's bytes; ValueError when they do not verify."""
    head, _, body = data.partition(b"\n")
    header = json.loads(head)
    if (header["format"], header["key"]) != (FORMAT, key):
        raise ValueError("a cache file of another format or key")
    if header["sha256"] != _sha(body):
        raise ValueError("a corrupt cache file")
    first, *lines, build, end = body.split(b"\n")
    if end or len(lines) != len(header["ids"]):
        raise ValueError("a cache file whose episodes do not match its ids")
    content = json.loads(first)
    return FilePart(
        {s: Scene.model_validate(scene) for s, scene in content["scenes"].items()},
        {label: Behaviour.model_validate(b) for label, b in content["training"].items()},
        tuple(header["ids"]), tuple(lines), build)


def _whole(specs: Path) -> Episodes:
    """The specs compiled together, uncached (see the module docstring): SpecErrors on bad
    specs."""
    from robofollow.benchmark.pipeline import compile_specs

    return of(compile_specs(specs))


def of(compiled) -> Episodes:
    """A `compiled.Compiled` as the cache holds it (what evaluating, serving and recording
    demonstrations read)."""
    from robofollow.benchmark.render import episodes

    return Episodes(compiled.spec, dict(compiled.training), *episodes(compiled))


def _store(path: Path, data: bytes) -> None:
    """Write atomically (a temporary file renamed into place), then keep the newest KEEP."""
    partial = path.with_name(f".{path.name}.{os.getpid()}-{secrets.token_hex(4)}")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        partial.write_bytes(data)
        os.replace(partial, path)
    except OSError as error:
        partial.unlink(missing_ok=True)
        warnings.warn(f"cannot cache the compiled benchmark in {path.parent}: "
                      f"{error.strerror or error}", RuntimeWarning, stacklevel=4)
        return
    try:
        with os.scandir(path.parent) as entries:
            files = sorted((entry.stat().st_mtime_ns, entry.path) for entry in entries
                           if entry.name.endswith(".jsonl") and not entry.name.startswith("."))
        for _, old in files[:-KEEP]:
            os.unlink(old)
    except OSError:  # another process pruning at the same time
        pass
