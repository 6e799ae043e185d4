"""Files shipped with the package (the grammars, the built-in benchmark specs and its frozen
releases), and where RoboFollow keeps what it caches."""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path

# In a wheel the top-level grammar/ folder is installed as robofollow/grammar; in a source
# checkout it sits beside the package.
_SOURCE = Path(__file__).resolve().parent.parent
_SOURCE_GRAMMARS = _SOURCE / "grammar"


def grammar_text(name: str) -> str:
    """The text of a grammar file, e.g. 'instruction.lark'."""
    packaged = resources.files("robofollow").joinpath("grammar", name)
    if packaged.is_file():
        return packaged.read_text(encoding="utf-8")
    return (_SOURCE_GRAMMARS / name).read_text(encoding="utf-8")


def builtin_specs() -> Path:
    """The folder of the benchmark's own .rf specs (installed with the package)."""
    packaged = Path(str(resources.files("robofollow").joinpath("specs")))
    return packaged if packaged.is_dir() else _SOURCE / "specs"


def releases_dir() -> Path:
    """The folder of the frozen benchmark releases (robofollow/releases, shipped in the
    package)."""
    return Path(__file__).resolve().parent / "releases"


def cache_root() -> Path | None:
    """Where RoboFollow caches what it derives from its code and specs (compiled benchmarks,
    parser tables): $ROBOFOLLOW_CACHE_DIR, else $XDG_CACHE_HOME/robofollow, else
    ~/.cache/robofollow; None when ROBOFOLLOW_NO_CACHE=1 turns caching off."""
    if os.environ.get("ROBOFOLLOW_NO_CACHE", "") not in ("", "0"):
        return None
    root = os.environ.get("ROBOFOLLOW_CACHE_DIR") or Path(
        os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "robofollow"
    return Path(root)
