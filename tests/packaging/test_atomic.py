"""tribocosim.atomic: a file is written whole or not at all, and an interrupted or failed write leaves the old file
as it was and no temporary file behind."""

from __future__ import annotations

import pytest

from tribocosim import atomic


def test_a_written_file_replaces_the_old_one_whole(tmp_path):
    path = tmp_path / "a.txt"
    path.write_text("old")
    atomic.write_text(path, "new\n")
    assert path.read_text() == "new\n" and sorted(p.name for p in tmp_path.iterdir()) == ["a.txt"]
    atomic.write_bytes(path, b"\x00\x01")
    assert path.read_bytes() == b"\x00\x01"


@pytest.mark.parametrize("error", [KeyboardInterrupt, SystemExit, OSError])
def test_an_interrupted_writer_leaves_the_old_file_and_nothing_else(tmp_path, error):
    path = tmp_path / "table.npz"
    path.write_bytes(b"old")
    with pytest.raises(error):
        with atomic.replaced(path, ".npz") as tmp:
            assert tmp.parent == tmp_path and tmp.name.endswith(".npz") and tmp.name.startswith(".")
            tmp.write_bytes(b"half")
            raise error()
    assert path.read_bytes() == b"old" and sorted(p.name for p in tmp_path.iterdir()) == ["table.npz"]


def test_a_file_set_is_written_all_or_none(tmp_path):
    a, b = tmp_path / "a.k", tmp_path / "missing" / "b.k"
    a.write_text("old")
    with pytest.raises(OSError):
        atomic.write_all({a: "new", b: "new"})
    assert a.read_text() == "old" and sorted(p.name for p in tmp_path.iterdir()) == ["a.k"]
    assert atomic.write_all({a: "A", tmp_path / "c.k": b"C"}) == [a, tmp_path / "c.k"]
    assert a.read_text() == "A" and (tmp_path / "c.k").read_bytes() == b"C"
