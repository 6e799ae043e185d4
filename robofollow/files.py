"""File helpers for every floor: JSON and JSON Lines writing and reading, atomic writes,
links, where a byte that is not UTF-8 sits."""

from __future__ import annotations

import json
import os
import shutil
from collections.abc import Iterator
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any


def write_json(path: Path, data) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")


def json_line(record, sort_keys: bool = False) -> str:
    """One JSON Lines record with its newline. Text stays readable UTF-8, except U+2028 and
    U+2029, which are escaped: line-splitting readers (Python's str.splitlines, JavaScript)
    would break the record at them."""
    return _line_of(json.dumps(record, ensure_ascii=False, sort_keys=sort_keys))


_SORTED = json.JSONEncoder(ensure_ascii=False, sort_keys=True)  # as json_line(..., True)


def json_value(value) -> str:
    """A value as `json_line(..., sort_keys=True)` writes it inside a record."""
    return _SORTED.encode(value)


def json_line_of(encoded: dict[str, str]) -> str:
    """`json_line(record, sort_keys=True)` of a record whose values come encoded (json_value):
    records that share most of their values need them encoded once."""
    return _line_of("{" + ", ".join([_key(key) + encoded[key] for key in sorted(encoded)]) + "}")


@cache
def _key(key: str) -> str:
    """A record's key as json_line writes it, with the colon (the keys repeat record after
    record)."""
    return _SORTED.encode(key) + ": "


def _line_of(text: str) -> str:
    return text.replace("\u2028", "\\u2028").replace("\u2029", "\\u2029") + "\n"


def write_jsonl(path: Path, records) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", encoding="utf-8") as f:
        f.writelines(json_line(r) for r in records)


def write_bytes_atomic(path: Path, data: bytes) -> None:
    """Write through a temporary file and rename: readers see the old file or the new one
    (and a write that fails, e.g. on a full disk, leaves no temporary file behind)."""
    partial = path.with_name(path.name + ".partial")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        partial.write_bytes(data)
        os.replace(partial, path)
    except BaseException:
        partial.unlink(missing_ok=True)
        raise


def write_json_atomic(path: Path, data) -> None:
    """JSON written atomically (write_bytes_atomic), as write_json writes it."""
    write_bytes_atomic(path, (json.dumps(data, indent=2) + "\n").encode())


def link_or_copy(source: Path, target: Path) -> None:
    """Hard-link a file into the dataset (no second copy on disk), else copy it."""
    target.parent.mkdir(parents=True, exist_ok=True)
    try:
        os.link(source, target)
    except OSError:
        shutil.copyfile(source, target)


def changed_options(previous: dict, current: dict) -> str | None:
    """Why a run cannot be resumed with `current` options, or None when they are the same."""
    changed = [key for key, value in current.items() if previous.get(key) != value]
    if not changed:
        return None
    return (f"was run with other options ({', '.join(changed)} differ); resume with the same "
            "options or choose another folder")


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
    return line, column, shown, (f"the file is not UTF-8 text: byte 0x{data[start]:02x} "
                                 f"({error.reason})")


@dataclass(frozen=True)
class JsonLine:
    """One line of JSON Lines data: its number (from 1), its bytes, and its value, or what
    is wrong with it: `problem` says it ("not UTF-8 text (byte 0xff)", "not JSON (...)"),
    `column` where (in characters), `text` whether it was UTF-8 text at least."""

    number: int
    raw: bytes
    value: Any = None
    problem: str | None = None
    column: int | None = None
    text: bool = True


def json_lines(data: bytes) -> Iterator[JsonLine]:
    """The lines of JSON Lines data that are not blank, split at newlines only (U+2028 and
    U+2029 stay inside their record)."""
    for number, raw in enumerate(data.split(b"\n"), start=1):
        if not raw.strip():
            continue
        try:
            value = json.loads(raw.decode("utf-8"))
        except UnicodeDecodeError as error:
            _, column, _, _ = not_utf8(raw, error)
            yield JsonLine(number, raw, problem=f"not UTF-8 text (byte 0x{raw[error.start]:02x})",
                           column=column, text=False)
        except json.JSONDecodeError as error:
            yield JsonLine(number, raw, problem=f"not JSON ({error.msg} at column "
                                                f"{error.colno})", column=error.colno)
        else:
            yield JsonLine(number, raw, value)
