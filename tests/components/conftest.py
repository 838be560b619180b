"""Session fixtures for the FMU tests: all FMUs are built once per session, in a subprocess.

- ``built_fmus``: ``tribocosim fmu build --out TMP`` (the command line) -> ``{name: path}``;
- ``stripdraw_fmu_*``: the StripDraw FMU (file, extracted folder, model description, instances);
- ``fmu_unzipped``, ``fmu_description``, ``fmu_instance``: the same for any FMU, by name;
- ``numpy_fmpy_venv``: a throwaway virtual environment with only numpy and fmpy (from the
  package registry), shared by the tests that run the FMUs outside this project's environment.

Fixture names start with ``stripdraw_fmu``/``fmu_``/``built_fmus`` so that they do not collide with
other fixtures of ``tests/components``.

Beside them, for the friction exports: ``velocity_dependent_table``, the shipped table with its particle-borne area at
0.5 m/s made 30 % smaller (the shipped table's law does not depend on the velocity, so an export writes it at one
velocity; this one keeps the velocity axis).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tribocosim.components.stripdraw.model import OUTPUT_NAMES

PROJECT_ROOT = Path(__file__).resolve().parents[2]
#: the FMUs ``tribocosim fmu build`` builds, in its order (the components' folders, alphabetically)
FMU_NAMES = ("DrawingMachine", "Press", "StripDraw")

#: Real outputs of the StripDraw FMU, in the model's order (``table_clamp_count`` is an Integer output)
REAL_OUTPUTS = tuple(name for name in OUTPUT_NAMES if name != "table_clamp_count")


@pytest.fixture(scope="session")
def built_fmus(tmp_path_factory) -> dict[str, Path]:
    """``tribocosim fmu build --platform linux64 --out TMP`` (the command line, in a subprocess): the FMUs with this
    machine's binary; ``{name: FMU file}``."""
    out = tmp_path_factory.mktemp("fmus")
    proc = subprocess.run(
        [sys.executable, "-m", "tribocosim.cli", "fmu", "build", "--platform", "linux64", "--out", str(out)],
        cwd=PROJECT_ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, f"tribocosim fmu build failed:\n{proc.stdout}\n{proc.stderr}"
    printed = [Path(line) for line in proc.stdout.split()]
    expected = [out.resolve() / f"{name}.fmu" for name in FMU_NAMES]
    assert printed == expected, f"unexpected output of fmu build: {proc.stdout!r}"
    return dict(zip(FMU_NAMES, printed))


@pytest.fixture(scope="session")
def stripdraw_fmu_file(built_fmus) -> Path:
    """The built StripDraw FMU."""
    return built_fmus["StripDraw"]


@pytest.fixture(scope="session")
def fmu_unzipped(built_fmus, tmp_path_factory):
    """``unzipped(name) -> Path``: the FMU extracted once per session (fmpy loads its binary from here)."""
    from fmpy import extract

    cache: dict[str, Path] = {}

    def unzipped(name: str) -> Path:
        if name not in cache:
            cache[name] = Path(extract(str(built_fmus[name]), str(tmp_path_factory.mktemp(f"{name}_unzipped"))))
        return cache[name]

    return unzipped


@pytest.fixture(scope="session")
def fmu_description(built_fmus):
    """``description(name)``: the FMU's model description (fmpy), read once per session."""
    from fmpy import read_model_description

    cache = {}

    def description(name: str):
        if name not in cache:
            cache[name] = read_model_description(str(built_fmus[name]))
        return cache[name]

    return description


@pytest.fixture(scope="session")
def stripdraw_fmu_unzipped(fmu_unzipped) -> Path:
    """The StripDraw FMU extracted once (fmpy loads its binary from here)."""
    return fmu_unzipped("StripDraw")


@pytest.fixture(scope="session")
def stripdraw_fmu_description(fmu_description):
    """The StripDraw FMU's model description (fmpy)."""
    return fmu_description("StripDraw")


class FmuInstance:
    """One fmpy ``FMU2Slave`` instance of one of our FMUs that collects its log messages.

    Parameters are set in initialization mode; :meth:`initialize` leaves it. :meth:`step` sets
    the inputs ``input_names`` (in that order), does one step and returns the Real outputs
    ``output_names``.
    """

    def __init__(self, unzipped: Path, description, name: str, parameters: dict | None = None,
                 input_names=(), output_names=()):  # fmt: skip
        from fmpy import calloc, free
        from fmpy.fmi2 import (
            FMU2Slave,
            fmi2CallbackAllocateMemoryTYPE,
            fmi2CallbackFreeMemoryTYPE,
            fmi2CallbackFunctions,
            fmi2CallbackLoggerTYPE,
        )

        self.messages: list[tuple[int, str]] = []
        self.variables = {v.name: v for v in description.modelVariables}
        callbacks = fmi2CallbackFunctions()
        callbacks.logger = fmi2CallbackLoggerTYPE(self._log)
        callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        self._callbacks = callbacks  # keep the ctypes callbacks alive
        self.slave = FMU2Slave(
            guid=description.guid,
            unzipDirectory=str(unzipped),
            modelIdentifier=description.coSimulation.modelIdentifier,
            instanceName=name,
        )
        self.slave.instantiate(callbacks=callbacks, loggingOn=True)
        self.slave.setupExperiment(startTime=0.0)
        self.slave.enterInitializationMode()
        for key, value in (parameters or {}).items():
            self.set(key, value)
        self._real_vrs = [self.variables[n].valueReference for n in output_names]
        self._input_vrs = [self.variables[n].valueReference for n in input_names]
        self.time = 0.0

    def _log(self, env, instance, status, category, message):
        self.messages.append((int(status), message.decode("utf-8", "replace")))

    def set(self, name: str, value) -> None:
        """Set one variable by name, with the setter of its type."""
        var = self.variables[name]
        vr = [var.valueReference]
        if var.type == "Real":
            self.slave.setReal(vr, [float(value)])
        elif var.type == "Integer":
            self.slave.setInteger(vr, [int(value)])
        elif var.type == "String":
            self.slave.setString(vr, [str(value)])
        else:  # pragma: no cover - the FMUs have no Boolean variables
            raise TypeError(var.type)

    def initialize(self):
        self.slave.exitInitializationMode()
        return self

    def outputs(self) -> np.ndarray:
        """The Real outputs ``output_names``."""
        return np.array(self.slave.getReal(self._real_vrs))

    def step(self, dt: float, *inputs: float) -> np.ndarray:
        """Set the inputs, doStep from the instance's time by ``dt``, return :meth:`outputs`."""
        if self._input_vrs:
            self.slave.setReal(self._input_vrs, list(inputs))
        self.slave.doStep(self.time, dt)
        self.time += dt
        return self.outputs()

    def free(self) -> None:
        try:
            self.slave.terminate()
        except Exception:  # noqa: BLE001 - an instance a test left in an error state
            pass
        self.slave.freeInstance()


class StripDrawFmuInstance(FmuInstance):
    """One instance of StripDraw: ``step(dt, normal_force, grip_velocity)`` returns the Real
    outputs (REAL_OUTPUTS order) followed by ``table_clamp_count``."""

    #: the columns of :meth:`outputs`
    OUTPUT_NAMES = (*REAL_OUTPUTS, "table_clamp_count")

    def __init__(self, unzipped: Path, description, name: str, parameters: dict | None = None):
        super().__init__(unzipped, description, name, parameters, ("normal_force", "grip_velocity"), REAL_OUTPUTS)
        self._clamp_vr = self.variables["table_clamp_count"].valueReference

    def outputs(self) -> np.ndarray:
        """Real outputs (REAL_OUTPUTS order) followed by table_clamp_count."""
        reals = self.slave.getReal(self._real_vrs)
        return np.array([*reals, float(self.slave.getInteger([self._clamp_vr])[0])])


@pytest.fixture
def stripdraw_fmu_instance(stripdraw_fmu_unzipped, stripdraw_fmu_description):
    """Factory ``make(name, parameters=None) -> StripDrawFmuInstance`` (in initialization mode).

    Every instance made is freed at the end of the test.
    """
    made = []

    def make(name: str, parameters: dict | None = None) -> StripDrawFmuInstance:
        inst = StripDrawFmuInstance(stripdraw_fmu_unzipped, stripdraw_fmu_description, name, parameters)
        made.append(inst)
        return inst

    yield make
    for inst in made:
        inst.free()


@pytest.fixture
def fmu_instance(fmu_unzipped, fmu_description):
    """Factory ``make(fmu, name, parameters=None, inputs=(), outputs=()) -> FmuInstance`` (in
    initialization mode) for the FMU named ``fmu``. Every instance made is freed at the end of the test."""
    made = []

    def make(fmu: str, name: str, parameters: dict | None = None, inputs=(), outputs=()) -> FmuInstance:
        inst = FmuInstance(fmu_unzipped(fmu), fmu_description(fmu), name, parameters, inputs, outputs)
        made.append(inst)
        return inst

    yield make
    for inst in made:
        inst.free()


def clean_env() -> dict:
    """The environment without Python/virtualenv/numba settings of this session (for other interpreters)."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "VIRTUAL_ENV", "NUMBA"))}
    env["PIP_DISABLE_PIP_VERSION_CHECK"] = "1"
    return env


@pytest.fixture(scope="session")
def numpy_fmpy_venv(tmp_path_factory) -> tuple[Path, dict]:
    """``(python, env)``: the interpreter of a throwaway virtual environment with only numpy and fmpy
    (pip, from the package registry), and the environment to run it in (:func:`clean_env`)."""
    venv = tmp_path_factory.mktemp("numpy_fmpy") / "venv"
    env = clean_env()
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, env=env, timeout=300)
    python = venv / "bin" / "python"
    pip = subprocess.run(
        [str(python), "-m", "pip", "install", "--quiet", "numpy", "fmpy"],
        env=env, capture_output=True, text=True, timeout=900,
    )  # fmt: skip
    assert pip.returncode == 0, f"pip install numpy fmpy failed (the registry must be reachable):\n{pip.stderr}"
    return python, env


@pytest.fixture(scope="session")
def velocity_dependent_table(tmp_path_factory) -> Path:
    """The shipped table with A_p (and its spread and standard errors) times 0.7 in its 0.5 m/s row, so that the law
    falls off less with debris at the higher speed: a table whose law depends on the velocity, for the exports'
    velocity axis (the module docstring)."""
    import dataclasses

    from tribocosim.components.stripdraw.table import read_table, write_table
    from tribocosim.paths import DEFAULT_TABLE

    table = read_table(DEFAULT_TABLE)
    factor = np.ones(table.velocity.size)
    factor[table.velocity == 0.5] = 0.7
    scale = factor[None, :, None]
    extras = {k: (v * scale if k in ("particle_area_se", "particle_area_clusters", "particle_area_clusters_se", "mu_se")
                  else v) for k, v in table.extras.items()}
    meta = {k: v for k, v in table.metadata.items() if k != "content_hash"}
    meta["note"] = "the shipped table with A_p x 0.7 at 0.5 m/s (a test's table)"
    path = tmp_path_factory.mktemp("tables") / "velocity_dependent.npz"
    write_table(path, dataclasses.replace(table, particle_area=table.particle_area * scale,
                                          particle_area_std=table.particle_area_std * scale, extras=extras,
                                          metadata=meta))
    return path
