"""Session fixtures for the FMU tests: the StripDraw FMU is built once per session, in a subprocess.

Fixture names start with ``stripdraw_fmu`` so that they do not collide with other fixtures of
``tests/components``.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

PROJECT_ROOT = Path(__file__).resolve().parents[2]

#: Real outputs of the FMU, in the model's order (``table_clamp_count`` is an Integer output)
REAL_OUTPUTS = (
    "pull_force",
    "friction_force",
    "mu_mean",
    "sliding_distance",
    "beta_mean",
    "beta_max",
    "contact_pressure",
    "grip_position",
)


@pytest.fixture(scope="session")
def stripdraw_fmu_file(tmp_path_factory) -> Path:
    """``tribocosim fmu build --out TMP`` (the command line, in a subprocess); the built FMU."""
    out = tmp_path_factory.mktemp("fmus")
    proc = subprocess.run(
        [sys.executable, "-m", "cosim.cli", "fmu", "build", "--out", str(out)],
        cwd=PROJECT_ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, f"tribocosim fmu build failed:\n{proc.stdout}\n{proc.stderr}"
    printed = [Path(line) for line in proc.stdout.split()]
    assert printed == [out.resolve() / "StripDraw.fmu"], f"unexpected output of fmu build: {proc.stdout!r}"
    return printed[0]


@pytest.fixture(scope="session")
def stripdraw_fmu_unzipped(stripdraw_fmu_file, tmp_path_factory) -> Path:
    """The FMU extracted once (fmpy loads its binary from here)."""
    from fmpy import extract

    return Path(extract(str(stripdraw_fmu_file), str(tmp_path_factory.mktemp("fmu_unzipped"))))


@pytest.fixture(scope="session")
def stripdraw_fmu_description(stripdraw_fmu_file):
    """The FMU's model description (fmpy)."""
    from fmpy import read_model_description

    return read_model_description(str(stripdraw_fmu_file))


class StripDrawFmuInstance:
    """One fmpy ``FMU2Slave`` instance of StripDraw that collects its log messages.

    Parameters are set in initialization mode; :meth:`initialize` leaves it.
    """

    #: the columns of :meth:`outputs`
    OUTPUT_NAMES = (*REAL_OUTPUTS, "table_clamp_count")

    def __init__(self, unzipped: Path, description, name: str, parameters: dict | None = None):
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
        self._real_vrs = [self.variables[n].valueReference for n in REAL_OUTPUTS]
        self._clamp_vr = self.variables["table_clamp_count"].valueReference
        self._input_vrs = [self.variables[n].valueReference for n in ("normal_force", "grip_velocity")]
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
        else:  # pragma: no cover - the FMU has no Boolean variables
            raise TypeError(var.type)

    def initialize(self) -> "StripDrawFmuInstance":
        self.slave.exitInitializationMode()
        return self

    def outputs(self) -> np.ndarray:
        """Real outputs (REAL_OUTPUTS order) followed by table_clamp_count."""
        reals = self.slave.getReal(self._real_vrs)
        return np.array([*reals, float(self.slave.getInteger([self._clamp_vr])[0])])

    def step(self, dt: float, normal_force: float, grip_velocity: float) -> np.ndarray:
        """Set the inputs, doStep from the instance's time by ``dt``, return :meth:`outputs`."""
        self.slave.setReal(self._input_vrs, [normal_force, grip_velocity])
        self.slave.doStep(self.time, dt)
        self.time += dt
        return self.outputs()

    def free(self) -> None:
        try:
            self.slave.terminate()
        except Exception:  # noqa: BLE001 - an instance a test left in an error state
            pass
        self.slave.freeInstance()


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
