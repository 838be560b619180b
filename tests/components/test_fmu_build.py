"""tribocosim.components.fmus.build and ``tribocosim fmu``: what goes into an FMU, and the failures that name their cause."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from tribocosim.components.fmus import build, cli



def _modules(name: str) -> set[str]:
    return set(build.runtime_modules(name))


def test_runtime_modules_are_the_import_closure_of_the_adapter():
    mods = _modules("StripDraw")
    must = {
        "tribocosim",
        "tribocosim.components",
        "tribocosim.components.errors",
        "tribocosim.components.fmus",
        "tribocosim.components.fmus.statecodec",
        "tribocosim.components.stripdraw",
        "tribocosim.components.stripdraw.model",
        "tribocosim.components.stripdraw.friction",
        "tribocosim.components.stripdraw.table",
        "tribocosim.components.stripdraw.parameters",
        "tribocosim.components.stripdraw.kernels",
    }
    assert must <= mods, sorted(must - mods)
    assert all(m.startswith("tribocosim") for m in mods), sorted(mods)
    assert not mods & {"tribocosim.components.fmus.build", "tribocosim.components.fmus.cli",
                       "tribocosim.components.fmus.StripDraw", "tribocosim.cosim", "tribocosim.surrogate"}
    files = build.runtime_files("StripDraw")
    assert all(f.suffix == ".py" and f.is_file() for f in files)


@pytest.mark.parametrize("name, model", [("Press", "press"), ("DrawingMachine", "machine")])
def test_press_and_machine_bundle_their_model_and_the_shared_plumbing_only(name, model):
    assert _modules(name) == {
        "tribocosim",
        "tribocosim.components",
        "tribocosim.components.errors",
        "tribocosim.components.params",
        "tribocosim.components.linear",
        f"tribocosim.components.{model}",
        "tribocosim.components.fmus",
        "tribocosim.components.fmus.adapter",
        "tribocosim.components.fmus.statecodec",
        "tribocosim.components.fmus.exitguard",
    }
    assert build.FMUS[name].data == (), "no friction table"
    assert "tribocosim.components.fmus.adapter" in _modules("StripDraw"), "StripDraw uses the same adapter plumbing"


def _fake_adapter(tmp_path, monkeypatch, body: str, name: str = "Fake") -> str:
    """An adapter module ``fakepkg_<test>.<name>`` in a temporary folder (a package name of its own per
    test: find_spec imports the package)."""
    pkg = tmp_path / f"fakepkg_{tmp_path.name}"
    pkg.mkdir(exist_ok=True)
    (pkg / "__init__.py").write_text("")
    (pkg / f"{name}.py").write_text(body.replace("fakepkg_adapters", pkg.name))
    monkeypatch.syspath_prepend(str(tmp_path))
    return f"{pkg.name}.{name}"


def test_missing_module_or_data_file_fails_the_build_naming_it(tmp_path, monkeypatch):
    adapter = _fake_adapter(tmp_path, monkeypatch, "from tribocosim.components.stripdraw.nope import x\n")
    monkeypatch.setitem(build.FMUS, "Fake", build.FmuSpec(adapter, data=(tmp_path / "absent.npz",)))
    with pytest.raises(build.FmuBuildError, match=r"FMU Fake: required file .*absent\.npz is missing"):
        build.build_fmus(tmp_path / "out", names=["Fake"])
    monkeypatch.setitem(build.FMUS, "Fake", build.FmuSpec(adapter))
    with pytest.raises(build.FmuBuildError, match=r"missing modules: tribocosim\.components\.stripdraw\.nope"):
        build.build_fmus(tmp_path / "out", names=["Fake"])
    assert not list((tmp_path / "out").glob("*.fmu")), "a failed build left an FMU behind"


def test_every_fmu_is_checked_before_any_is_built(tmp_path, monkeypatch):
    adapter = _fake_adapter(tmp_path, monkeypatch, "import tribocosim.components.gone\n")
    monkeypatch.setitem(build.FMUS, "Fake", build.FmuSpec(adapter))
    missing = r"FMU Fake: the adapter imports missing modules: tribocosim\.components\.gone"
    with pytest.raises(build.FmuBuildError, match=missing):
        build.build_fmus(tmp_path / "out", names=["Press", "Fake"])
    assert not list((tmp_path / "out").glob("*.fmu")), "Press was built although the build failed"


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


def test_source_digest_changes_with_any_bundled_file(tmp_path, monkeypatch):
    table = tmp_path / "table.npz"
    table.write_bytes(b"first")
    adapter = _fake_adapter(tmp_path, monkeypatch, "from fakepkg_adapters import helper\nimport tribocosim.components.press\n")
    helper = tmp_path / adapter.split(".")[0] / "helper.py"
    helper.write_text("x = 1\n")
    monkeypatch.setitem(build.FMUS, "Fake", build.FmuSpec(adapter, data=(table,)))
    before = build.source_digest("Fake")
    table.write_bytes(b"second")
    assert build.source_digest("Fake") != before, "the data file is covered"
    before = build.source_digest("Fake")
    (tmp_path / adapter.split(".")[0] / "Fake.py").write_text("import tribocosim.components.press\n# edited\n")
    assert build.source_digest("Fake") != before, "the adapter is covered"
    # only tribocosim modules are bundled and digested: the press's closure, not the strip's
    assert "tribocosim.components.press" in build.runtime_modules("Fake")
    assert "tribocosim.components.stripdraw.model" not in build.runtime_modules("Fake")
    assert build.source_digest("Press") != build.source_digest("StripDraw")


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
        "StripDraw", "tribocosim.components.fmus.StripDraw",
        "Press", "tribocosim.components.fmus.Press",
        "DrawingMachine", "tribocosim.components.fmus.DrawingMachine",
    ]  # fmt: skip
    assert cli.main(["build", "--out", str(tmp_path), "--only", "Nope"]) == 1
    assert "unknown FMU 'Nope'" in capsys.readouterr().err
