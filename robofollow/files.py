"""File helpers for every floor: JSON and JSON Lines writing and reading, atomic writes,
links, where a byte that is not UTF-8 sits."""

from __future__ import annotations

import json
import math
import os
import shutil
import stat
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any, BinaryIO


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
        partial.unlink(missing_ok=True)  # (a link left there is not followed)
        partial.write_bytes(data)
        os.replace(partial, path)
    except BaseException:
        partial.unlink(missing_ok=True)
        raise


def json_bytes(data) -> bytes:
    """A JSON file's bytes, as write_json writes them."""
    return (json.dumps(data, indent=2) + "\n").encode()


def write_json_atomic(path: Path, data) -> None:
    """JSON written atomically (write_bytes_atomic), as write_json writes it."""
    write_bytes_atomic(path, json_bytes(data))


def link_or_copy(source: Path, target: Path) -> None:
    """Hard-link a file into the dataset (no second copy on disk), else copy it."""
    target.parent.mkdir(parents=True, exist_ok=True)
    try:
        os.link(source, target)
    except OSError:
        shutil.copyfile(source, target)


RECORDED = ("provenance",)  # what a run records beside its options (not an option)


def differing_options(previous: dict, current: dict) -> list[str]:
    """The options in which two runs differ, every option of either side compared (one that
    only one side has differs), in `current`'s order then `previous`'s."""
    keys = [*current, *(key for key in previous if key not in current)]
    return [key for key in keys if key not in RECORDED and previous.get(key) != current.get(key)]


def changed_options(previous: dict, current: dict) -> str | None:
    """Why a run cannot be resumed with `current` options, or None when they are the same."""
    changed = differing_options(previous, current)
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
        except RecursionError:
            yield JsonLine(number, raw, problem=f"not JSON ({NESTED})")
        else:
            yield JsonLine(number, raw, value)


# -- reading files that may be bad -------------------------------------------------------------
# Helpers for the validating readers of RoboFollow's files (each names the file itself): they
# return what is wrong, in words, or raise nothing.

NESTED = "nested too deeply"  # JSON whose arrays and objects nest past the parser's depth


def read_at_most(stream: BinaryIO, limit: int) -> bytes | None:
    """The stream's bytes, or None when it holds more than `limit`: reading stops there, so a
    small compressed stream (gzip.open) cannot fill the memory."""
    data = stream.read(limit + 1)
    return data if len(data) <= limit else None


def not_regular(mode: int) -> str | None:
    """Why a file of this st_mode is not read as data ("a folder", "a FIFO, socket or device"),
    or None for a regular file."""
    if stat.S_ISREG(mode):
        return None
    return ("a folder, not a file" if stat.S_ISDIR(mode)
            else "not a regular file (a FIFO, socket or device)")


def file_problem(path: Path, limit: int) -> str | None:
    """Why a file (its links followed) is not read as data of at most `limit` bytes: it cannot
    be looked at, is not a regular file (not_regular), or is larger; None when it may be read.
    For readers that hand the path on (np.load); the others use read_file_at_most."""
    try:
        info = os.stat(path)
    except OSError as error:
        return f"cannot be read ({error.strerror or error})"
    return not_regular(info.st_mode) or _size_problem(info.st_size, limit)


def _size_problem(size: int, limit: int) -> str | None:
    return f"larger than {size_text(limit)}" if size > limit else None


def size_text(limit: int) -> str:
    """A size limit as messages give it: "16 MiB", "512 bytes"."""
    return f"{limit >> 20} MiB" if limit >= 1 << 20 else f"{limit} bytes"


def read_file_at_most(path: Path, limit: int) -> tuple[bytes | None, str | None]:
    """(the file's bytes, None), or (None, why not: "cannot be read (...)", "larger than
    16 MiB", not_regular's reasons). Opened without blocking (a FIFO never hangs) and checked
    once open; at most limit + 1 bytes are read (a file that grows, or a link to /dev/zero,
    cannot fill the memory)."""
    try:
        descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except OSError as error:
        return None, f"cannot be read ({error.strerror or error})"
    try:
        with os.fdopen(descriptor, "rb") as stream:
            info = os.fstat(descriptor)
            problem = not_regular(info.st_mode) or _size_problem(info.st_size, limit)
            data = None if problem else read_at_most(stream, limit)
    except OSError as error:
        return None, f"cannot be read ({error.strerror or error})"
    if problem:
        return None, problem
    return (data, None) if data is not None else (None, f"larger than {size_text(limit)}")


def read_json_file(path: Path, limit: int) -> tuple[Any, str | None]:
    """(the JSON document a file holds, None), or (None, why not: read_file_at_most's
    reasons, or json_document's)."""
    data, problem = read_file_at_most(path, limit)
    return (None, problem) if problem else json_document(data)


def read_json_object(path: Path, limit: int) -> tuple[dict | None, str | None]:
    """(the JSON object a file holds, None), or (None, why not: read_json_file's reasons, or
    "a JSON array, not an object")."""
    value, problem = read_json_file(path, limit)
    if problem is None and not isinstance(value, dict):
        problem = f"a JSON {json_type(value)}, not an object"
    return (None, problem) if problem else (value, None)


def json_document(data: bytes) -> tuple[Any, str | None]:
    """(value, None) of a whole JSON document, or (None, what is wrong: "line 3, column 7:
    not JSON (Expecting value)", "line 1, column 2: not UTF-8 text (byte 0xff)")."""
    try:
        return json.loads(data.decode("utf-8")), None
    except UnicodeDecodeError as error:
        line, column, _, _ = not_utf8(data, error)
        return None, (f"line {line}, column {column}: not UTF-8 text "
                      f"(byte 0x{data[error.start]:02x})")
    except json.JSONDecodeError as error:
        return None, f"line {error.lineno}, column {error.colno}: not JSON ({error.msg})"
    except RecursionError:
        return None, f"not JSON ({NESTED})"


def json_type(value) -> str:
    """The JSON name of a value's type: "object", "array", "string", "boolean", "null",
    "number"."""
    return {dict: "object", list: "array", str: "string", bool: "boolean",
            type(None): "null"}.get(type(value), "number")


def shown(value, width: int = 40) -> str:
    """A value as a message quotes it: JSON, on one line, cut to about `width` characters."""
    try:
        text = json.dumps(value[:width + 1] if isinstance(value, str) else value,
                          ensure_ascii=True)
    except (TypeError, ValueError, RecursionError):
        text = f"a {type(value).__name__}"
    return text if len(text) <= width else text[:width] + "…"


def number_problem(value, low: float | None = None, high: float | None = None) -> str | None:
    """What is wrong with a value that must be a finite number (not a bool) from `low` to
    `high`, or None: 'is "a", not a number', "is nan, not a finite number", "is 500, not a
    number from 0 to 1"."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return f"is {shown(value)}, not a number"
    if not math.isfinite(float(value) if abs(value) < 2 ** 1000 else math.inf):
        return f"is {shown(value)}, not a finite number"
    if (low is not None and value < low) or (high is not None and value > high):
        bounds = (f"a number from {low:g} to {high:g}" if low is not None and high is not None
                  else f"at least {low:g}" if low is not None else f"at most {high:g}")
        return f"is {value:g}, not {bounds}"
    return None


def key_problem(data: dict, required: Iterable[str], optional: Iterable[str] = ()
                ) -> tuple[str, str] | None:
    """The first key an object lacks ("missing", key) or has beyond `required` and `optional`
    ("unknown", key), or None."""
    known = {*required, *optional}
    for key in required:
        if key not in data:
            return "missing", key
    for key in data:
        if key not in known:
            return "unknown", key
    return None
