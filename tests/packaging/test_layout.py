"""The distribution's layout: one import name, every subpackage listed, package data, a lazy top level."""

from __future__ import annotations

import subprocess
import sys
import tomllib
from pathlib import Path

import tribocosim

ROOT = Path(__file__).resolve().parents[2]


def test_every_source_folder_with_an_init_is_a_listed_package():
    cfg = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    mapping = cfg["package-dir"]
    listed = set(cfg["packages"])
    expected = set()
    for name, folder in mapping.items():
        for init in (ROOT / folder).rglob("__init__.py"):
            rel = init.parent.relative_to(ROOT / folder)
            expected.add(".".join([name, *rel.parts]))
    assert expected <= listed, f"pyproject packages: missing {sorted(expected - listed)}"
    for extra in listed - expected:  # data folders (no __init__.py): they must exist and hold files
        top = max((n for n in mapping if extra.startswith(n + ".") or extra == n), key=len)
        folder = ROOT / mapping[top] / Path(*extra[len(top) + 1:].split("."))
        assert folder.is_dir() and any(folder.iterdir()), f"{extra}: {folder} is not a data folder"
    assert all(p == "tribocosim" or p.startswith("tribocosim.") for p in listed), "one import name"


def test_package_data_is_found_through_the_package():
    from tribocosim.paths import DEFAULT_TABLE, SCENES_DIR

    assert DEFAULT_TABLE.is_file() and (SCENES_DIR / "demo.toml").is_file()
    table = tribocosim.read_table(tribocosim.DEFAULT_TABLE)
    assert table.provenance == "mesoscale"


def test_import_tribocosim_is_lazy_and_offers_the_public_api():
    script = ("import sys, tribocosim\n"
              "loaded = {m for m in sys.modules if m.startswith('tribocosim.')}\n"
              "assert loaded <= {'tribocosim.lazy', 'tribocosim.public'}, sorted(loaded)\n"
              "print(tribocosim.run.__module__, tribocosim.StripDrawModel.__module__)\n"
              "p = tribocosim.StripDrawParameters(friction_model='closed_form')\n"
              "tribocosim.StripDrawModel(p, tribocosim.make_friction_law(p)).step(1e-3, {'normal_force': 1e4, "
              "'grip_velocity': 0.08})\n"
              "print('numba' in sys.modules)\n")
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    mods, numba = proc.stdout.split("\n")[:2]
    assert mods == "tribocosim.cosim.apps.scripting tribocosim.components.stripdraw.model"
    assert numba == "False", "the model is the native core: no numba"
    assert set(tribocosim.__all__) >= {"run", "StripDrawModel", "StripDrawParameters", "read_table", "FrictionTable"}


def test_the_readme_example_runs_beside_a_clone_named_tribocosim(tmp_path):
    """From the folder that holds a clone named ``tribocosim``, Python imports the clone's folder as the package (the
    current directory comes first on sys.path): the repository's __init__.py makes it the package the clone holds, so
    the README's strip-draw example runs there on the clone's own code."""
    clone = tmp_path / "tribocosim"
    subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True, timeout=120)
    for name in ("__init__.py", "tribocosim/__init__.py", "tribocosim/public.py"):  # this tree's, committed or not
        (clone / name).write_text((ROOT / name).read_text())
    script = ("import tribocosim\n"
              "from tribocosim import DEFAULT_TABLE, StripDrawModel, StripDrawParameters, make_friction_law, read_table\n"
              "p = StripDrawParameters()\n"
              "model = StripDrawModel(p, make_friction_law(p, read_table(DEFAULT_TABLE)))\n"
              "out = model.step(1e-3, {'normal_force': 12250.0, 'grip_velocity': 0.008})\n"
              "import tribocosim.components.stripdraw.model as m\n"
              "print(tribocosim.__file__, DEFAULT_TABLE, m.__file__, out['pull_force'] > 0)\n")
    out = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    init, table, model, pulled = out.stdout.split()
    assert init == str(clone / "__init__.py") and table == str(clone / "models" / "friction_table.npz")
    assert model == str(clone / "components" / "stripdraw" / "model.py") and pulled == "True"
