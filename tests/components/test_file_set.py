"""The files of an export: their names, and all of them written or none."""

from __future__ import annotations

from pathlib import Path

import pytest

from tribocosim.errors import ParameterError
from tribocosim.components.friction_export.file_set import tagged, write_all


def test_names_insert_the_state_and_the_band_before_the_suffix():
    assert tagged(Path("out/friction.k"), "pass2", "upper") == Path("out/friction.pass2.upper.k")
    assert tagged(Path("friction.k"), "", "lower") == Path("friction.lower.k")
    assert tagged(Path("friction.k"), "", "") == Path("friction.k")
    assert tagged(Path("friction"), "upper") == Path("friction.upper")


def test_every_file_is_written_or_none(tmp_path):
    written = write_all({tmp_path / "a.k": "A\n", tmp_path / "b.k": "B\n"})
    assert [p.read_text() for p in written] == ["A\n", "B\n"]
    (tmp_path / "c.k").mkdir()  # a folder where the second file should go
    with pytest.raises(ParameterError, match="is a folder"):
        write_all({tmp_path / "a.k": "new\n", tmp_path / "c.k": "C\n"})
    assert (tmp_path / "a.k").read_text() == "A\n", "the first file is not replaced when the set fails"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.k", "b.k", "c.k"], "no temporary file left"


def test_a_file_that_cannot_be_written_leaves_nothing(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(ParameterError, match="-o .*does not exist or is not a folder"):
        write_all({tmp_path / "ok.k": "A\n", blocker / "friction.k": "B\n"})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]
