"""Reading .rf spec files, and the source lines that errors show.

Only regular files are read (a FIFO or device named *.rf is refused unopened), a symbolic link
found in a spec folder that points out of it is refused unfollowed, and a file is at most
MAX_SPEC_BYTES long. Text that is not UTF-8 is refused at its first bad byte (line:column).
"""

from __future__ import annotations

import os
import stat
from dataclasses import dataclass, field
from pathlib import Path

from robofollow.compiler.scene.spec import MAX_SPEC_BYTES, Source
from robofollow.errors import SpecError
from robofollow.files import not_regular, not_utf8, read_file_at_most

SPEC_SUFFIX = ".rf"


def spec_files(paths: list[Path] | Path) -> list[Path]:
    """The .rf files named, or found below the folders named, in a stable order."""
    return [path for path, _ in found_files(paths)]


def found_files(paths: list[Path] | Path) -> list[tuple[Path, Path | None]]:
    """(file, the folder it was found in, or None when it was named itself), in a stable
    order. Finding opens nothing: what is found is checked before it is read."""
    files: list[tuple[Path, Path | None]] = []
    for path in [paths] if isinstance(paths, Path) else paths:
        if path.is_dir():
            files.extend((file, path) for file in sorted(path.rglob(f"*{SPEC_SUFFIX}")))
        else:
            files.append((path, None))
    return files


def spec_text(path: Path, folder: Path | None) -> str | SpecError:
    """The file's text, or why it is not read (an error at 1:1, or at the first byte that is
    not UTF-8)."""
    why = _why_not_read(path, folder)
    data = None
    if why is None:
        data, why = read_file_at_most(path, MAX_SPEC_BYTES)  # (checked again once open: the
        #   file may have been replaced since it was looked at)
    if data is None:
        return SpecError("unreadable", why, file=str(path), line=1, column=1)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as error:
        line, column, shown, message = not_utf8(data, error)
        return SpecError("encoding", message, file=str(path), line=line, column=column,
                         source_line=shown)


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
    if not_regular(info.st_mode):
        return f"{not_regular(info.st_mode)}; it is not read"
    if info.st_size > MAX_SPEC_BYTES:
        return (f"{info.st_size} bytes, more than a spec file may hold ({MAX_SPEC_BYTES} "
                "bytes)")
    return None


def split_lines(text: str) -> tuple[str, ...]:
    """Lines as the spec parser counts them: split at '\n' only (a '\r' before it dropped)."""
    return tuple(line.removesuffix("\r") for line in text.split("\n"))


@dataclass
class Sources:
    """The lines of spec files by file, as loading read them. A file not held is read when a
    line of it is asked for (a spec checked apart from its loading: `check_training`)."""

    lines: dict[str, tuple[str, ...]] = field(default_factory=dict)

    def line(self, where: Source) -> str:
        """The line `where` points at ('' when there is none)."""
        lines = self.lines[where.file] if where.file in self.lines else _reread(where.file)
        return lines[where.line - 1] if 0 < where.line <= len(lines) else ""


def _reread(file: str) -> tuple[str, ...]:
    data, _ = read_file_at_most(Path(file), MAX_SPEC_BYTES)
    return () if data is None else split_lines(data.decode("utf-8", errors="replace"))


def spec_error(code: str, message: str, where: Source, sources: Sources,
               length: int = 1, hints: tuple[str, ...] = (),
               severity: str = "error") -> SpecError:
    """A SpecError (or a warning) at `where`, showing its source line (and `hints` under
    it)."""
    return SpecError(code, message, file=where.file, line=where.line, column=where.column,
                     source_line=sources.line(where), length=length, hints=hints,
                     severity=severity)
