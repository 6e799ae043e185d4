"""Small file helpers shared by the dataset writers."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path


def write_json(path: Path, data) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")


def json_line(record, sort_keys: bool = False) -> str:
    """One JSON Lines record with its newline. Text stays readable UTF-8, except U+2028 and
    U+2029, which are escaped: line-splitting readers (Python's str.splitlines, JavaScript)
    would break the record at them."""
    text = json.dumps(record, ensure_ascii=False, sort_keys=sort_keys)
    return text.replace("\u2028", "\\u2028").replace("\u2029", "\\u2029") + "\n"


def write_jsonl(path: Path, records) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", encoding="utf-8") as f:
        f.writelines(json_line(r) for r in records)


def write_json_atomic(path: Path, data) -> None:
    """Write through a temporary file and rename: readers see the old file or the new one
    (and a write that fails, e.g. on a full disk, leaves no temporary file behind)."""
    partial = path.with_name(path.name + ".partial")
    try:
        write_json(partial, data)
        os.replace(partial, path)
    except BaseException:
        partial.unlink(missing_ok=True)
        raise


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
