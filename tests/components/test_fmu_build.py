"""``tribocosim fmu`` and the build's records: what it builds, where, and the failures that name their cause."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tribocosim.components.fmus import fmu_cli, native_build


def test_build_record_holds_the_source_digest(built_fmus):
    for name, fmu in built_fmus.items():
        record = json.loads(Path(f"{fmu}.json").read_text())
        assert record["name"] == name and record["variant"] == "native"
        assert record["source_digest"] == native_build.source_digest(name)
    assert not list(fmu.parent.glob(".*partial*")), "partial files left behind"


def test_unknown_fmu_name_is_refused_before_building(tmp_path):
    known = "DrawingMachine, Press, StripDraw"
    with pytest.raises(native_build.FmuBuildError, match=f"unknown native FMU 'Nope'; this project builds: {known}"):
        native_build.build_native_fmus(tmp_path, names=["StripDraw", "Nope"], platforms=["linux64"])
    assert list(tmp_path.iterdir()) == []


def test_cli_builds_into_a_relative_folder(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert fmu_cli.main(["build", "--out", "rel/fmus", "--only", "Press", "--platform", "linux64"]) == 0
    out = capsys.readouterr()
    printed = out.out.split()
    assert printed == [str(tmp_path / "rel" / "fmus" / "Press.fmu")] and Path(printed[0]).is_file()
    # progress on stderr while it compiles: one line per FMU and platform, one before validating
    assert out.err.splitlines() == ["tribocosim fmu build: compiling Press (FMI 2.0) for linux64 (1/1)",
                                    "tribocosim fmu build: validating Press.fmu (fmpy validate)"], out.err


def test_cli_lists_and_reports_errors(capsys, tmp_path):
    assert fmu_cli.main(["list"]) == 0
    assert capsys.readouterr().out.split() == [
        "DrawingMachine", "tribocosim.components.machine.component",
        "Press", "tribocosim.components.press.component",
        "StripDraw", "tribocosim.components.stripdraw.component",
    ]  # fmt: skip
    assert fmu_cli.main(["build", "--out", str(tmp_path), "--only", "Nope"]) == 1
    assert "unknown native FMU 'Nope'" in capsys.readouterr().err


def test_the_project_builds_no_python_variant(capsys):
    """One FMI layer for the project's physics: the C one (a component in Python is a pythonfmu FMU of its own)."""
    with pytest.raises(SystemExit) as exc:
        fmu_cli.main(["build", "--python"])
    assert exc.value.code == 2 and "--python" in capsys.readouterr().err
