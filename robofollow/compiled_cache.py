"""The compiled benchmark as an env reads it, cached on disk so that an env starts without
compiling the specs (seconds) every time.

An env needs the spec (its scenes) and the episode records. They are kept in one JSON Lines
file per key, `<cache>/compiled/<key>.jsonl`: a header (format, key, episode ids, the sha256 of
the rest), the spec, then one episode per line as the build writes `episodes/*.jsonl`; an
episode is parsed when asked for. The key is a sha256 over the specs' path, every spec file's
name and bytes, FORMAT, RoboFollow's version and the compiler's code and grammars (SOURCES), so
a change to any of them compiles again. A file is written to a temporary name and renamed into
place; one that does not verify (corrupt, truncated, stale) is compiled again and replaced.

`<cache>` is $ROBOFOLLOW_CACHE_DIR, else $XDG_CACHE_HOME/robofollow, else ~/.cache/robofollow;
ROBOFOLLOW_NO_CACHE=1 turns the disk cache off (each process then compiles once).
"""

from __future__ import annotations

import hashlib
import json
import os
import secrets
import warnings
from dataclasses import dataclass
from functools import cache, cached_property, lru_cache
from importlib import metadata
from pathlib import Path

from robofollow.benchmark.episode import Episode
from robofollow.compiler.spec import LEVELS, Spec
from robofollow.compiler.spec_files import spec_files
from robofollow.files import json_line
from robofollow.resources import cache_root

FORMAT = 1  # bump when the file layout or the records' meaning changes
KEEP = 8  # cache files kept (the newest); older ones are removed when one is written
# the code the compile runs, under robofollow/ (a test checks that these are the modules the
# cached compile imports, and beside them only the rest of the compiler): a change to it, and
# only to it, compiles again
SOURCES = ("benchmark/__init__.py", "benchmark/episode.py", "benchmark/pipeline.py",
           "benchmark/rounds.py", "compiled_cache.py", "errors.py", "resources.py", "files.py",
           "compiler", "audit")


@dataclass(frozen=True)
class Episodes:
    """The spec and every episode (in `benchmark.rounds.all_episodes` order), each parsed when asked
    for (a fresh object every time)."""

    spec: Spec
    ids: tuple[str, ...]
    lines: tuple[bytes, ...]

    @cached_property
    def index(self) -> dict[str, int]:
        return {episode: i for i, episode in enumerate(self.ids)}

    def record(self, episode_id: str) -> Episode:
        """The episode with this id (`<scene>/<level>/<task>#r<round>`)."""
        if episode_id not in self.index:
            raise _unknown(episode_id, self.ids)
        return Episode.model_validate_json(self.lines[self.index[episode_id]])

    def select(self, scene: str | None = None, level: str | None = None) -> tuple[str, ...]:
        """The ids of the episodes of a scene and a level (None: any)."""
        chosen = tuple(episode for episode in self.ids
                       if scene in (None, episode.split("/", 1)[0])
                       and level in (None, episode.split("/", 2)[1]))
        if not chosen:
            raise ValueError(f"no episodes of scene {scene!r} at level {level!r} (scenes: "
                             f"{', '.join(self.spec.scenes)}; levels: {', '.join(LEVELS)})")
        return chosen


def _unknown(episode_id: str, ids: tuple[str, ...]) -> Exception:
    from robofollow.benchmark.rounds import unknown_episode  # (imports the compiler: only on error)

    return unknown_episode(episode_id, list(dict.fromkeys(e.partition("#")[0] for e in ids)))


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


def key(specs: Path) -> str:
    """The cache key of a specs folder (or file) as it is now."""
    specs = Path(os.path.realpath(specs))
    digest = hashlib.sha256(f"{code_digest()}\0{specs}\0".encode())
    for path in spec_files(specs):
        name = path.relative_to(specs) if path != specs else path.name
        digest.update(f"{name}\0".encode() + path.read_bytes() + b"\0")
    return digest.hexdigest()


def load(specs: Path) -> Episodes:
    """The compiled benchmark of `specs`: from the cache when it holds it, else compiled (and
    cached). Raises SpecErrors on bad specs; a cache that cannot be read or written is only
    passed over."""
    specs = Path(os.path.realpath(specs))
    try:
        digest = key(specs)
    except OSError:  # an unreadable spec file: the compile says so
        return _parse(_compile(specs, ""), "")
    return _load(specs, digest, cache_dir())


@lru_cache(maxsize=4)
def _load(specs: Path, digest: str, folder: Path | None) -> Episodes:
    """One read (or compile) per specs state and cache folder, per process."""
    path = folder / f"{digest}.jsonl" if folder else None
    if path is not None:
        try:
            return _parse(path.read_bytes(), digest)
        except Exception:  # missing, corrupt, truncated or stale: compile it again
            pass
    data = _compile(specs, digest)
    if path is not None:
        _store(path, data)
    return _parse(data, digest)


def _compile(specs: Path, digest: str) -> bytes:
    """The cache file's bytes for `specs`, compiled."""
    from robofollow.benchmark.pipeline import compile_specs  # (seconds: only on a miss)
    from robofollow.benchmark.rounds import episode_records, ordered_tasks

    compiled = compile_specs(specs)
    records = [record for task in ordered_tasks(compiled)
               for record in episode_records(compiled, task)]
    body = (compiled.spec.model_dump_json() + "\n"
            + "".join(json_line(record, sort_keys=True) for record in records)).encode()
    header = {"format": FORMAT, "key": digest, "sha256": hashlib.sha256(body).hexdigest(),
              "ids": [record["episode"] for record in records]}
    return json.dumps(header).encode() + b"\n" + body


def _parse(data: bytes, digest: str) -> Episodes:
    """The Episodes of a cache file's bytes; ValueError when they do not verify."""
    head, _, body = data.partition(b"\n")
    header = json.loads(head)
    if (header["format"], header["key"]) != (FORMAT, digest):
        raise ValueError("a cache file of another format or key")
    if header["sha256"] != hashlib.sha256(body).hexdigest():
        raise ValueError("a corrupt cache file")
    spec, *lines, end = body.split(b"\n")
    if end or len(lines) != len(header["ids"]):
        raise ValueError("a cache file whose episodes do not match its ids")
    return Episodes(Spec.model_validate_json(spec), tuple(header["ids"]), tuple(lines))


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
                      f"{error.strerror or error}", RuntimeWarning, stacklevel=3)
        return
    try:
        with os.scandir(path.parent) as entries:
            files = sorted((entry.stat().st_mtime_ns, entry.path) for entry in entries
                           if entry.name.endswith(".jsonl") and not entry.name.startswith("."))
        for _, old in files[:-KEEP]:
            os.unlink(old)
    except OSError:  # another process pruning at the same time
        pass
