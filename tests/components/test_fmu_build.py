"""tribocosim.components.fmus.python_build and ``tribocosim fmu``: what goes into an FMU, and the failures that name their cause."""

from __future__ import annotations

import importlib
import json
import shutil
from pathlib import Path

import pytest

from tribocosim.components.fmus import fmu_cli, python_build



def _modules(name: str) -> set[str]:
    return set(python_build.runtime_modules(name))


def test_runtime_modules_are_the_import_closure_of_the_adapter():
    mods = _modules("StripDraw")
    must = {
        "tribocosim",
        "tribocosim.components",
        "tribocosim.errors",
        "tribocosim.components.fmus",
        "tribocosim.components.fmus.statecodec",
        "tribocosim.components.stripdraw",
        "tribocosim.components.stripdraw.model",
        "tribocosim.components.stripdraw.friction",
        "tribocosim.components.stripdraw.table",
        "tribocosim.components.stripdraw.parameters",
        "tribocosim.components.native.toolchain.library",
    }
    assert must <= mods, sorted(must - mods)
    assert all(m.startswith("tribocosim") for m in mods), sorted(mods)
    assert not mods & {"tribocosim.components.fmus.python_build", "tribocosim.components.fmus.fmu_cli",
                       "tribocosim.paths", "tribocosim.cosim", "tribocosim.surrogate"}
    files = python_build.runtime_files("StripDraw")
    assert all(f.suffix == ".py" and f.is_file() for f in files)


@pytest.mark.parametrize("name, model", [("Press", "press"), ("DrawingMachine", "machine")])
def test_press_and_machine_bundle_their_model_and_the_shared_plumbing_only(name, model):
    assert _modules(name) == {
        "tribocosim",
        "tribocosim.components",
        "tribocosim.errors",
        "tribocosim.components.params",
        "tribocosim.components.description",
        "tribocosim.components.native",  # the binding of the native core (built by the FMU's builder)
        "tribocosim.components.native.toolchain",
        "tribocosim.components.native.toolchain.library",
        "tribocosim.components.native.toolchain.compiler",
        "tribocosim.components.native.toolchain.declarations",
        "tribocosim.components.linear_model",
        "tribocosim.components.registry",
        f"tribocosim.components.{model}",
        f"tribocosim.components.{model}.component",
        f"tribocosim.components.{model}.model",
        f"tribocosim.components.{model}.parameters",
        "tribocosim.components.fmus",
        "tribocosim.components.fmus.adapter",
        "tribocosim.components.fmus.statecodec",
        "tribocosim.components.fmus.exitguard",
        "tribocosim.components.fmus.modeldescription",
        "tribocosim.lazy",
    }
    assert python_build.component(name).resources == (), "no friction table"
    assert "tribocosim.components.fmus.adapter" in _modules("StripDraw"), "StripDraw uses the same adapter plumbing"


EXTRA = Path(__file__).resolve().parent / "extra"


def test_a_registered_component_is_an_fmu_with_its_own_modules_bundled(lag_component):
    assert python_build.fmus()["Lag"] is lag_component
    mods = _modules("Lag")
    assert {"lagcomponent", "lagcomponent.component", "lagcomponent.model",
            "tribocosim.components.fmus.adapter", "tribocosim.components.description"} <= mods
    assert not [m for m in mods if m.startswith(("tribocosim.components.stripdraw", "tribocosim.components.press"))]


def _lag_copy(tmp_path, monkeypatch, name: str, resources: str = "", solver: bool = False):
    """A registered copy of the test component, as package ``name`` in ``tmp_path`` (to break or edit)."""
    import shutil

    from tribocosim.components import registry

    pkg = tmp_path / name
    shutil.copytree(EXTRA / "lagcomponent", pkg, ignore=shutil.ignore_patterns("__pycache__"))
    for f in pkg.glob("*.py"):
        f.write_text(f.read_text().replace("lagcomponent", name))
    comp = pkg / "component.py"
    if resources:
        comp.write_text(comp.read_text().replace("    build=build,", f"    build=build,\n    resources={resources},"))
    if solver:  # build() imports a module that does not exist
        comp.write_text(comp.read_text().replace(f"from {name}.model import LagModel", f"from {name}.solver import LagModel"))
    monkeypatch.syspath_prepend(str(tmp_path))
    comp = importlib.import_module(f"{name}.component").COMPONENT
    monkeypatch.setattr(registry, "_REGISTERED", dict(registry._REGISTERED))  # undone after the test
    registry.register(comp)
    return pkg, comp


def test_missing_module_or_data_file_fails_the_build_naming_it(tmp_path, monkeypatch):
    _lag_copy(tmp_path, monkeypatch, "lagnodata", resources='(("lagnodata", "absent.npz"),)')
    with pytest.raises(python_build.FmuBuildError, match=r"FMU Lag: required file .*absent\.npz is missing"):
        python_build.build_fmus(tmp_path / "out", names=["Lag"])
    _lag_copy(tmp_path, monkeypatch, "lagnomodel", solver=True)
    with pytest.raises(python_build.FmuBuildError, match=r"missing modules: lagnomodel\.solver"):
        python_build.build_fmus(tmp_path / "out", names=["Lag"])
    assert not list((tmp_path / "out").glob("*.fmu")), "a failed build left an FMU behind"


def test_every_fmu_is_checked_before_any_is_built(tmp_path, monkeypatch):
    _lag_copy(tmp_path, monkeypatch, "lagcheck", solver=True)
    missing = r"FMU Lag: the adapter imports missing modules: lagcheck\.solver"
    with pytest.raises(python_build.FmuBuildError, match=missing):
        python_build.build_fmus(tmp_path / "out", names=["Press", "Lag"])
    assert not list((tmp_path / "out").glob("*.fmu")), "Press was built although the build failed"


def test_unknown_fmu_name_is_refused_before_building(tmp_path):
    known = "DrawingMachine, Press, StripDraw"
    with pytest.raises(python_build.FmuBuildError, match=f"unknown FMU 'Nope'; this project builds: {known}"):
        python_build.build_fmus(tmp_path, names=["StripDraw", "Nope"])
    assert list(tmp_path.iterdir()) == []


def test_build_record_holds_the_source_digest(built_fmus):
    for name, fmu in built_fmus.items():
        record = json.loads(Path(f"{fmu}.json").read_text())
        assert record["name"] == name
        assert record["source_digest"] == python_build.source_digest(name)
    assert not list(fmu.parent.glob(".*partial*")), "partial files left behind"


def test_source_digest_changes_with_any_bundled_file(tmp_path, monkeypatch):
    pkg, _ = _lag_copy(tmp_path, monkeypatch, "lagdigest", resources='(("lagdigest", "data.bin"),)')
    (pkg / "data.bin").write_bytes(b"first")
    before = python_build.source_digest("Lag")
    (pkg / "data.bin").write_bytes(b"second")
    assert python_build.source_digest("Lag") != before, "the resource file is covered"
    before = python_build.source_digest("Lag")
    (pkg / "model.py").write_text((pkg / "model.py").read_text() + "\n# edited\n")
    assert python_build.source_digest("Lag") != before, "the model module is covered"
    press = python_build.source_digest("Press")
    assert python_build.source_digest("Press") == press and press != python_build.source_digest("StripDraw")


def test_cli_builds_into_a_relative_folder(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert fmu_cli.main(["build", "--python", "--out", "rel/fmus"]) == 0
    printed = capsys.readouterr().out.split()
    names = ("DrawingMachine", "Press", "StripDraw")
    assert printed == [str(tmp_path / "rel" / "fmus" / f"{name}.fmu") for name in names]
    assert all(Path(p).is_file() for p in printed)


def test_cli_lists_and_reports_errors(capsys, tmp_path):
    assert fmu_cli.main(["list"]) == 0
    assert capsys.readouterr().out.split() == [
        "DrawingMachine", "tribocosim.components.machine.component",
        "Press", "tribocosim.components.press.component",
        "StripDraw", "tribocosim.components.stripdraw.component",
    ]  # fmt: skip
    assert fmu_cli.main(["build", "--python", "--out", str(tmp_path), "--only", "Nope"]) == 1
    assert "unknown FMU 'Nope'" in capsys.readouterr().err
