"""Fixtures of the co-simulation tests: the test FMUs, built once per session.

Each pythonfmu script in ``tests/cosim/fmus`` is built in its own subprocess (pythonfmu caches
the slave module by name inside a process), with ``--handle-state`` into ``fmus/`` and once more
without it into ``fmus-nostate/`` (FMUs that cannot roll back).
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from tribocosim.cosim.reports.oscfmus import CONNECTIONS

HERE = Path(__file__).resolve().parent
SCRIPTS = HERE / "fmus"
NAMES = ("OscMassA", "OscMassB", "LoopGain", "Fragile", "Lag")
NOSTATE = ("OscMassA", "OscMassB", "Fragile")

#: the exact solution of the reference two-mass oscillator at t = 10 s
X1_EXACT = 0.051040814057
X2_EXACT = 0.031641338373


def _build(script: Path, dest: Path, handle_state: bool) -> subprocess.Popen:
    cmd = [sys.executable, "-m", "pythonfmu", "build", "-f", str(script), "--dest", str(dest)]
    if handle_state:
        cmd.append("--handle-state")
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


@pytest.fixture(scope="session")
def fmu_dir(tmp_path_factory) -> Path:
    """Folder with the test FMUs; ``fmu_dir / "nostate"`` holds the ones without state handling."""
    root = tmp_path_factory.mktemp("cosim-fmus")
    (root / "nostate").mkdir()
    jobs = [(_build(SCRIPTS / f"{n}.py", root, True), n) for n in NAMES]
    jobs += [(_build(SCRIPTS / f"{n}.py", root / "nostate", False), n) for n in NOSTATE]
    for proc, name in jobs:
        out, _ = proc.communicate(timeout=300)
        assert proc.returncode == 0, f"building {name} failed:\n{out}"
    return root


def write_scene(folder: Path, name: str, text: str) -> Path:
    """Write a scene file (dedented) and return its path."""
    path = folder / name
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


def oscillator_scene(folder: Path, fmus: Path, *, name: str = "osc.toml", stop: float = 10.0, step: float = 0.01,
                     algorithm: str = "jacobi", extrapolation: int = 0, k2: float = 10.0, extra_master: str = "",
                     extra: str = "", output_update: str = "propagate") -> Path:
    """The two-mass oscillator split into two FMUs with force-displacement coupling."""
    return write_scene(folder, name, f"""
        [experiment]
        start = 0.0
        stop = {stop!r}
        step = {step!r}

        [master]
        algorithm = "{algorithm}"
        extrapolation = {extrapolation}
        output_update = "{output_update}"
        {extra_master}

        [fmus.a]
        path = "{fmus / 'OscMassA.fmu'}"
        parameters = {{ m = 1.0, k = 10.0, c = 0.2, x0 = 0.0, v0 = 0.0 }}

        [fmus.b]
        path = "{fmus / 'OscMassB.fmu'}"
        parameters = {{ m = 1.0, k3 = 20.0, c3 = 0.3, k2 = {k2!r}, c2 = 0.5, x0 = 0.5, v0 = 0.0 }}

        {textwrap.indent(CONNECTIONS, ' ' * 8).lstrip()}

        {extra}

        [output]
        file = "results.csv"
        variables = ["a.x1", "b.x2", "b.force"]
        """)


@pytest.fixture(scope="session")
def make_scene():
    """``make_scene(folder, name, text)``: write a scene file."""
    return write_scene


@pytest.fixture(scope="session")
def osc_scene(fmu_dir):
    """``osc_scene(folder, **options)``: the two-mass oscillator scene on the session's FMUs."""

    def make(folder: Path, *, fmus: Path | None = None, **kw) -> Path:
        return oscillator_scene(folder, fmus or fmu_dir, **kw)

    return make


@pytest.fixture(scope="session")
def exact_t10():
    """(x1, x2) of the reference oscillator at t = 10 s."""
    return X1_EXACT, X2_EXACT


@pytest.fixture(scope="session")
def known_area_table():
    """A version 2 table of known areas: A_c = P / 300 MPa, A_p / A_c = 16.4 beta (Eq. 23 with alpha = 3000), beta to
    1: flakes carry the whole contact at beta = 0.061 / s, inside the axis for s > 0.061."""
    import numpy as np

    from tribocosim.components.stripdraw.table import FrictionTable

    p, v, b = np.array([1e6, 10e6, 30e6]), np.array([0.0, 0.08, 0.5]), np.array([0.0, 0.02, 0.1, 0.5, 1.0])
    ap = 3000.0 * b[None, None, :] * p[:, None, None] / 55e9 * np.ones((3, 3, 5))
    ac = np.broadcast_to((p / 3e8)[:, None, None], (3, 3, 5)).copy()
    zeros = np.zeros((3, 3, 5))
    return FrictionTable(p, v, b, 0.15 * np.maximum(0.0, 1 - ap / ac), {"beta_threshold": 1.0}, contact_area=ac,
                         particle_area=ap, contact_area_std=zeros, particle_area_std=zeros)
