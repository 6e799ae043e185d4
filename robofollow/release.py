"""Benchmark releases: the compiled test set frozen as versioned data.

A release is what every command that runs or reads episodes needs, and nothing that has to be
compiled: the scenes (bodies, layouts, jitter), each training task's behaviour and every test
episode's record. It ships in the package as `releases/<name>/` (resources.releases_dir):

  benchmark.jsonl.gz  a head line (scenes, training behaviours, episode ids), then one episode
                      record per line, as the build writes `episodes/*.jsonl`
  manifest.json       the release's name and digest (sha256 of benchmark.jsonl, uncompressed),
                      the spec digest, each scene's split digest with its tasks and episodes
                      per level, the compiler code's digest, the scoring profile, and the
                      RoboFollow version and commit that froze it

A release never changes once frozen: `freeze` refuses a name that exists, and `load` refuses
a release whose data does not match its digest. CURRENT names the release commands read by
default; a new release is made current when its reference runs are done (docs/results)."""

from __future__ import annotations

import gzip
import hashlib
import json
import re
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING

from pydantic import ConfigDict

from robofollow import compiled_cache
from robofollow.benchmark.episode_hash import record_hash
from robofollow.compiled_cache import Episodes, code_digest, of
from robofollow.compiler.planning.profile import DEFAULT_PROFILE
from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.compiler.scene.model import Model
from robofollow.compiler.scene.spec import LEVELS, Scene, Spec
from robofollow.errors import RoboFollowError, did_you_mean
from robofollow.files import write_bytes_atomic, write_json_atomic
from robofollow.provenance import environment
from robofollow.resources import releases_dir

if TYPE_CHECKING:  # (the compiler loads only where a release is frozen)
    from robofollow.benchmark.compiled import Compiled

CURRENT = "v1"  # the release commands read by default
DATA = "benchmark.jsonl.gz"
MANIFEST = "manifest.json"
FORMAT = 1  # bump when the data's layout or the records' meaning changes
NAME = re.compile(r"v[0-9]+(\.[0-9]+)*")  # v1, v2, v2.1


class ReleaseError(RoboFollowError):
    """A release that does not exist, cannot be frozen, or does not match its digest."""


class SceneEntry(Model):
    """One scene of a release: its split digest, and its test tasks and episodes per level."""

    split: str
    tasks: dict[str, int]
    episodes: dict[str, int]


class Manifest(Model):
    """What a release holds and what froze it (RELEASE/manifest.json)."""

    model_config = ConfigDict(protected_namespaces=())

    format: int
    release: str
    digest: str  # sha256 of benchmark.jsonl (uncompressed)
    spec_digest: str
    code_digest: str  # the compiler's code (compiled_cache.code_digest)
    scenes: dict[str, SceneEntry]
    scoring: dict  # the scoring profile's fields
    robofollow: str
    commit: str | None

    @property
    def episodes(self) -> int:
        return sum(sum(scene.episodes.values()) for scene in self.scenes.values())


def names(folder: Path | None = None) -> list[str]:
    """The releases that ship, oldest first (v2 before v10)."""
    folder = folder or releases_dir()
    found = [p.name for p in folder.iterdir() if (p / MANIFEST).is_file()] if folder.is_dir() \
        else []
    return sorted(found, key=lambda name: tuple(int(n) for n in name[1:].split(".")))


def _folder(name: str, folder: Path | None = None) -> Path:
    """A shipped release's folder, or ReleaseError naming the releases there are."""
    known = names(folder)
    if name not in known:
        hint = did_you_mean(name, known)
        raise ReleaseError(f"no release {name!r} (releases: {', '.join(known) or 'none'})"
                           f"{'; ' + hint if hint else ''}")
    return (folder or releases_dir()) / name


def manifest(name: str, folder: Path | None = None) -> Manifest:
    """A release's manifest, checked."""
    path = _folder(name, folder) / MANIFEST
    try:
        found = Manifest.model_validate_json(path.read_bytes())
    except (OSError, ValueError) as error:
        raise ReleaseError(f"{path}: not a release manifest ({str(error).splitlines()[0]})") \
            from None
    if found.release != name or found.format != FORMAT:
        raise ReleaseError(f"{path}: the manifest of release {found.release!r}, format "
                           f"{found.format} (release {name!r}, format {FORMAT} expected)")
    return found


def load(name: str = CURRENT, folder: Path | None = None) -> Episodes:
    """The frozen benchmark of a release (read once per process): ReleaseError when there is
    no such release or its data does not match its digest."""
    return _load(name, folder or releases_dir())


@cache
def _load(name: str, folder: Path) -> Episodes:
    found = manifest(name, folder)
    path = folder / name / DATA
    try:
        data = gzip.decompress(path.read_bytes())
    except (OSError, EOFError, gzip.BadGzipFile) as error:
        raise ReleaseError(f"{path}: cannot be read ({error})") from None
    if hashlib.sha256(data).hexdigest() != found.digest:
        raise ReleaseError(f"{path}: its data does not match release {name}'s digest "
                           f"({found.digest[:16]}): the release is damaged")
    head, _, body = data.partition(b"\n")
    content = json.loads(head)
    lines = tuple(body.split(b"\n")[:-1])
    spec = Spec(scenes={s: Scene.model_validate(scene)
                        for s, scene in content["scenes"].items()},
                digest=found.spec_digest)
    return Episodes(spec, {label: Behaviour.model_validate(b)
                           for label, b in content["training"].items()},
                    tuple(content["ids"]), lines, release=name, release_digest=found.digest)


def benchmark(name: str | None = None, specs: Path | None = None) -> Episodes:
    """What a command reads: release `name` (default: CURRENT), or, with `specs`, an author's
    working compile of them (from the compile cache; not a release)."""
    if specs is not None:
        if name is not None:
            raise ReleaseError("a release or a working compile of specs: give one")
        return compiled_cache.load(Path(specs))
    return load(name or CURRENT)


def release_data(compiled: Compiled, episodes: Episodes) -> bytes:
    """A compiled benchmark as a release holds it (benchmark.jsonl, uncompressed), from its
    episodes as `compiled_cache.of` gives them."""
    head = {"scenes": {s: scene.model_dump(mode="json")
                       for s, scene in compiled.spec.scenes.items()},
            "training": {label: b.model_dump(mode="json")
                         for label, b in compiled.training.items()},
            "ids": list(episodes.ids)}
    return json.dumps(head).encode() + b"\n" + b"".join(line + b"\n" for line in episodes.lines)


def _per_level(ids: tuple[str, ...], scene: str) -> dict[str, int]:
    levels = [episode.split("/", 2)[1] for episode in ids if episode.split("/", 1)[0] == scene]
    return {level: levels.count(level) for level in LEVELS}


def release_manifest(compiled: Compiled, name: str, data: bytes,
                     ids: tuple[str, ...]) -> Manifest:
    """The manifest of `compiled` frozen as release `name` with these data and episode ids."""
    scenes = {scene: SceneEntry(split=digest,
                                tasks={level: len(compiled.splits.of(scene, level))
                                       for level in LEVELS},
                                episodes=_per_level(ids, scene))
              for scene, digest in compiled.split_digests.items()}
    return Manifest(format=FORMAT, release=name, digest=hashlib.sha256(data).hexdigest(),
                    spec_digest=compiled.spec.digest, code_digest=code_digest(),
                    scenes=scenes, scoring=DEFAULT_PROFILE.model_dump(mode="json"),
                    robofollow=environment()["robofollow"] or "unknown",
                    commit=environment()["commit"])


def check_new(name: str, folder: Path | None = None) -> Path:
    """The folder a new release `name` goes to; ReleaseError for a name that is taken or not
    of the form v1, v2.1."""
    if not NAME.fullmatch(name):
        raise ReleaseError(f"release name {name!r}: expected v followed by a version, such as "
                           "v2 or v2.1")
    if folder is None and not (releases_dir().parent.parent / "pyproject.toml").is_file():
        raise ReleaseError(f"RoboFollow is installed here ({releases_dir().parent}), not a "
                           "source checkout: releases are frozen in a checkout of the "
                           "project, never into an installed package")
    target = (folder or releases_dir()) / name
    if target.exists():
        raise ReleaseError(f"release {name} exists ({target}); a release never changes once "
                           "frozen: choose another name")
    return target


def freeze(compiled: Compiled, name: str, folder: Path | None = None) -> Manifest:
    """Freeze a compiled benchmark as release `name` (a new folder in `folder`, by default the
    package's releases); ReleaseError as `check_new` says."""
    target = check_new(name, folder)
    episodes = of(compiled)  # (every episode's record, built once)
    data = release_data(compiled, episodes)
    found = release_manifest(compiled, name, data, episodes.ids)
    target.mkdir(parents=True)
    write_bytes_atomic(target / DATA, gzip.compress(data, compresslevel=9, mtime=0))
    write_json_atomic(target / MANIFEST, found.model_dump(mode="json"))
    return found


def of_spec_digest(spec_digest: str, folder: Path | None = None) -> str | None:
    """The first release frozen from specs with this digest: what a run made before runs named
    their release was made on (every such run predates the releases)."""
    matching = [name for name in names(folder)
                if manifest(name, folder).spec_digest == spec_digest]
    return matching[0] if matching else None


def content_hashes(benchmark: Episodes) -> dict[str, str]:
    """Each episode's hash over what decides it (benchmark.episode_hash), by id, computed from
    the records: comparable across releases, whichever hash their records carry (v1's cover
    the whole scene)."""
    worlds: dict = {}
    scenes = benchmark.spec.scenes
    hashes = {}
    for episode, line in zip(benchmark.ids, benchmark.lines, strict=True):
        record = json.loads(line)
        hashes[episode] = record_hash(scenes[record["scene"]], record, worlds)
    return hashes


def _cell(episode: str) -> tuple[str, str]:
    scene, level, _ = episode.split("/", 2)
    return scene, level


def _counts(a: set[str], b: set[str], same: set[str]) -> dict[str, int]:
    return {"added": len(b - a), "removed": len(a - b), "changed": len((a & b) - same),
            "unchanged": len(same)}


def _tasks(episodes: set[str]) -> dict[str, set[str]]:
    """The episodes by task id."""
    grouped: dict[str, set[str]] = {}
    for episode in episodes:
        grouped.setdefault(episode.partition("#")[0], set()).add(episode)
    return grouped


def diff(a: Episodes, b: Episodes) -> list[dict]:
    """Per scene x level cell (A's scene order, then B's new scenes): the tasks and episodes
    added, removed, changed and unchanged from A to B. An episode is unchanged where both hold
    its id with the same content hash; a task, where both hold the same episodes of it, each
    unchanged. Each row also lists the unchanged episodes' ids ("same")."""
    hashes_a, hashes_b = content_hashes(a), content_hashes(b)
    same = {e for e in hashes_a if hashes_b.get(e) == hashes_a[e]}
    scenes = list(dict.fromkeys([*a.spec.scenes, *b.spec.scenes]))
    rows = []
    for scene in scenes:
        for level in LEVELS:
            in_a = {e for e in hashes_a if _cell(e) == (scene, level)}
            in_b = {e for e in hashes_b if _cell(e) == (scene, level)}
            if not in_a and not in_b:
                continue
            kept = same & in_a
            tasks_a, tasks_b = _tasks(in_a), _tasks(in_b)
            same_tasks = {t for t in tasks_a if tasks_b.get(t) == tasks_a[t]
                          and tasks_a[t] <= kept}
            rows.append({"scene": scene, "level": level,
                         "tasks": _counts(set(tasks_a), set(tasks_b), same_tasks),
                         "episodes": _counts(in_a, in_b, kept), "same": sorted(kept)})
    return rows
