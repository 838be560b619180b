"""components.fmus.build and ``tribocosim fmu``: what goes into an FMU, and the failures that name their cause."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from components.fmus import build, cli

PROJECT_ROOT = Path(__file__).resolve().parents[2]


def test_runtime_files_are_the_import_closure_of_the_adapter():
    files = {p.relative_to(PROJECT_ROOT).as_posix() for p in build.runtime_files("StripDraw")}
    must = {
        "components/__init__.py",
        "components/errors.py",
        "components/fmus/__init__.py",
        "components/fmus/statecodec.py",
        "components/stripdraw/__init__.py",
        "components/stripdraw/model.py",
        "components/stripdraw/friction.py",
        "components/stripdraw/table.py",
        "components/stripdraw/parameters.py",
        "components/stripdraw/kernels.py",
    }
    assert must <= files, sorted(must - files)
    assert all(f.startswith("components/") and f.endswith(".py") for f in files), sorted(files)
    assert not files & {"components/fmus/build.py", "components/fmus/cli.py", "components/fmus/StripDraw.py"}


def _copy_tree(tmp_path: Path, with_table: bool = True) -> Path:
    root = tmp_path / "tree"
    shutil.copytree(PROJECT_ROOT / "components", root / "components", ignore=shutil.ignore_patterns("__pycache__"))
    if with_table:
        (root / "models").mkdir()
        shutil.copy2(PROJECT_ROOT / "models" / "friction_table.npz", root / "models")
    return root


def test_missing_module_or_data_file_fails_the_build_naming_it(tmp_path):
    root = _copy_tree(tmp_path, with_table=False)
    with pytest.raises(build.FmuBuildError, match=r"models/friction_table\.npz is missing"):
        build.build_fmus(tmp_path / "out", root=root)
    (root / "models").mkdir()
    shutil.copy2(PROJECT_ROOT / "models" / "friction_table.npz", root / "models")
    (root / "components" / "stripdraw" / "mesh.py").unlink()
    with pytest.raises(build.FmuBuildError, match=r"missing modules: components\.stripdraw\.mesh"):
        build.build_fmus(tmp_path / "out", root=root)
    assert not list((tmp_path / "out").glob("*.fmu")), "a failed build left an FMU behind"


def test_unknown_fmu_name_is_refused_before_building(tmp_path):
    with pytest.raises(build.FmuBuildError, match="unknown FMU 'Press'; this project builds: StripDraw"):
        build.build_fmus(tmp_path, names=["StripDraw", "Press"])
    assert list(tmp_path.iterdir()) == []


def test_build_record_holds_the_source_digest(stripdraw_fmu_file):
    record = json.loads(Path(f"{stripdraw_fmu_file}.json").read_text())
    assert record["name"] == "StripDraw"
    assert record["source_digest"] == build.source_digest("StripDraw")
    assert not list(stripdraw_fmu_file.parent.glob(".*partial*")), "partial files left behind"


def test_source_digest_changes_with_any_bundled_file(tmp_path):
    root = _copy_tree(tmp_path)
    before = build.source_digest("StripDraw", root)
    table = root / "models" / "friction_table.npz"
    table.write_bytes(table.read_bytes() + b"\0")
    assert build.source_digest("StripDraw", root) != before


def test_cli_builds_into_a_relative_folder(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert cli.main(["build", "--out", "rel/fmus"]) == 0
    printed = capsys.readouterr().out.split()
    assert printed == [str(tmp_path / "rel" / "fmus" / "StripDraw.fmu")]
    assert Path(printed[0]).is_file()


def test_cli_lists_and_reports_errors(capsys, tmp_path):
    assert cli.main(["list"]) == 0
    assert capsys.readouterr().out.split() == ["StripDraw", "components/fmus/StripDraw.py"]
    assert cli.main(["build", "--out", str(tmp_path), "--only", "Nope"]) == 1
    assert "unknown FMU 'Nope'" in capsys.readouterr().err
