"""Cached LALR tables (robofollow.compiler.language.lark_tables): written once, read back unchanged,
rebuilt when corrupt, and not written when caching is off."""

from __future__ import annotations

from robofollow.compiler.language.lark_tables import cached_lark

GRAMMAR = 'start: "a" NAME\nNAME: /[a-z]+/\n%ignore " "\n'


def _tables(root):
    return [path for path in (root / "parser").iterdir() if not path.name.endswith(".lock")]


def test_tables_are_written_once_and_read_back(tmp_path, monkeypatch):
    monkeypatch.setenv("ROBOFOLLOW_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("ROBOFOLLOW_NO_CACHE", raising=False)
    first = cached_lark("probe", GRAMMAR).parse("a word")
    [tables] = _tables(tmp_path)
    written = tables.stat().st_mtime_ns, tables.read_bytes()
    assert cached_lark("probe", GRAMMAR).parse("a word") == first
    assert (tables.stat().st_mtime_ns, tables.read_bytes()) == written  # read, not rebuilt


def test_corrupt_tables_are_rebuilt(tmp_path, monkeypatch):
    monkeypatch.setenv("ROBOFOLLOW_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("ROBOFOLLOW_NO_CACHE", raising=False)
    expected = cached_lark("probe", GRAMMAR).parse("a word")
    [tables] = _tables(tmp_path)
    tables.write_bytes(b"not tables")
    assert cached_lark("probe", GRAMMAR).parse("a word") == expected
    assert tables.read_bytes() != b"not tables"


def test_no_tables_are_written_with_caching_off(tmp_path, monkeypatch):
    monkeypatch.setenv("ROBOFOLLOW_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("ROBOFOLLOW_NO_CACHE", "1")
    assert cached_lark("probe", GRAMMAR).parse("a word").data == "start"
    assert not (tmp_path / "parser").exists()
