"""Files shipped with the package: the grammars and the built-in benchmark specs."""

from __future__ import annotations

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
