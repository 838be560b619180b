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


@pytest.mark.parametrize("name, model", [("Press", "press"), ("DrawingMachine", "machine")])
def test_press_and_machine_bundle_their_model_and_the_shared_plumbing_only(name, model):
    files = {p.relative_to(PROJECT_ROOT).as_posix() for p in build.runtime_files(name)}
    assert files == {
        "components/__init__.py",
        "components/errors.py",
        "components/params.py",
        "components/linear.py",
        f"components/{model}.py",
        "components/fmus/__init__.py",
        "components/fmus/adapter.py",
        "components/fmus/statecodec.py",
        "components/fmus/exitguard.py",
    }
    assert build.FMUS[name].data == (), "no friction table"
    shared = {p.relative_to(PROJECT_ROOT).as_posix() for p in build.runtime_files("StripDraw")}
    assert "components/fmus/adapter.py" in shared, "StripDraw uses the same adapter plumbing"


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


def test_every_fmu_is_checked_before_any_is_built(tmp_path):
    root = _copy_tree(tmp_path)
    (root / "components" / "linear.py").unlink()  # needed by Press and DrawingMachine, not StripDraw
    missing = r"FMU Press: the adapter imports missing modules: components\.linear"
    with pytest.raises(build.FmuBuildError, match=missing):
        build.build_fmus(tmp_path / "out", root=root)
    assert not list((tmp_path / "out").glob("*.fmu")), "StripDraw was built although the build failed"


def test_unknown_fmu_name_is_refused_before_building(tmp_path):
    known = "StripDraw, Press, DrawingMachine"
    with pytest.raises(build.FmuBuildError, match=f"unknown FMU 'Nope'; this project builds: {known}"):
        build.build_fmus(tmp_path, names=["StripDraw", "Nope"])
    assert list(tmp_path.iterdir()) == []


def test_build_record_holds_the_source_digest(built_fmus):
    for name, fmu in built_fmus.items():
        record = json.loads(Path(f"{fmu}.json").read_text())
        assert record["name"] == name
        assert record["source_digest"] == build.source_digest(name)
    assert not list(fmu.parent.glob(".*partial*")), "partial files left behind"


def test_source_digest_changes_with_any_bundled_file(tmp_path):
    root = _copy_tree(tmp_path)
    before = build.source_digest("StripDraw", root)
    table = root / "models" / "friction_table.npz"
    table.write_bytes(table.read_bytes() + b"\0")
    assert build.source_digest("StripDraw", root) != before
    # the press's digest covers its own closure: a strip-draw change does not touch it
    press = build.source_digest("Press", root)
    mesh = root / "components" / "stripdraw" / "mesh.py"
    mesh.write_text(mesh.read_text() + "\n")
    assert build.source_digest("Press", root) == press
    press_py = root / "components" / "press.py"
    press_py.write_text(press_py.read_text() + "\n")
    assert build.source_digest("Press", root) != press


def test_cli_builds_into_a_relative_folder(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert cli.main(["build", "--out", "rel/fmus"]) == 0
    printed = capsys.readouterr().out.split()
    names = ("StripDraw", "Press", "DrawingMachine")
    assert printed == [str(tmp_path / "rel" / "fmus" / f"{name}.fmu") for name in names]
    assert all(Path(p).is_file() for p in printed)


def test_cli_lists_and_reports_errors(capsys, tmp_path):
    assert cli.main(["list"]) == 0
    assert capsys.readouterr().out.split() == [
        "StripDraw", "components/fmus/StripDraw.py",
        "Press", "components/fmus/Press.py",
        "DrawingMachine", "components/fmus/DrawingMachine.py",
    ]  # fmt: skip
    assert cli.main(["build", "--out", str(tmp_path), "--only", "Nope"]) == 1
    assert "unknown FMU 'Nope'" in capsys.readouterr().err
