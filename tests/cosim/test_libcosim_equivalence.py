"""The same fixed-step Jacobi scene run by libcosim (libcosimpy, an independent C++ master) and by ours.

libcosim reads each FMU's outputs right after its doStep and hands them on at the next step
(no re-evaluation of direct-feedthrough outputs at the communication point), so the scene uses
``output_update = "none"``, which is that semantics. libcosim counts time in integer
nanoseconds; the step 0.01 s is exactly 10_000_000 ns.
"""

import numpy as np
import pytest

from tribocosim.cosim import run

libcosimpy = pytest.importorskip("libcosimpy")
from libcosimpy.CosimExecution import CosimExecution  # noqa: E402
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level  # noqa: E402
from libcosimpy.CosimObserver import CosimObserver  # noqa: E402
from libcosimpy.CosimSlave import CosimLocalSlave  # noqa: E402

A_PARAMS = dict(m=1.0, k=10.0, c=0.2, x0=0.0, v0=0.0)
B_PARAMS = dict(m=1.0, k3=20.0, c3=0.3, k2=10.0, c2=0.5, x0=0.5, v0=0.0)


def run_libcosim(fmu_dir, h, stop):
    log_output_level(CosimLogLevel.WARNING)
    ex = CosimExecution.from_step_size(int(round(h * 1e9)))
    ia = ex.add_local_slave(CosimLocalSlave(str(fmu_dir / "OscMassA.fmu"), "a"))
    ib = ex.add_local_slave(CosimLocalSlave(str(fmu_dir / "OscMassB.fmu"), "b"))
    refs = {i: {v.name.decode(): v.reference for v in ex.slave_variables(i)} for i in (ia, ib)}
    for name, value in A_PARAMS.items():
        assert ex.real_initial_value(ia, refs[ia][name], value)
    for name, value in B_PARAMS.items():
        assert ex.real_initial_value(ib, refs[ib][name], value)
    assert ex.connect_real_variables(ib, refs[ib]["force"], ia, refs[ia]["force"]) == 0
    assert ex.connect_real_variables(ia, refs[ia]["x1"], ib, refs[ib]["x1"]) == 0
    assert ex.connect_real_variables(ia, refs[ia]["v1"], ib, refs[ib]["v1"]) == 0
    obs = CosimObserver.create_last_value()
    ex.add_observer(obs)
    rows = []
    for _ in range(int(round(stop / h))):
        assert ex.step(1), f"libcosim step failed: {ex.status()}"
        rows.append([obs.last_real_values(ia, [refs[ia]["x1"]])[0], obs.last_real_values(ib, [refs[ib]["x2"]])[0],
                     obs.last_real_values(ib, [refs[ib]["force"]])[0]])
    return np.array(rows)


def test_fixed_step_jacobi_matches_libcosim(tmp_path, osc_scene, fmu_dir):
    h, stop = 0.01, 3.0
    ref = run_libcosim(fmu_dir, h, stop)
    ours = run(osc_scene(tmp_path, stop=stop, step=h, output_update="none"), write=False)
    got = np.column_stack([ours["a.x1"], ours["b.x2"], ours["b.force"]])[1:]
    assert got.shape == ref.shape
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-12, err_msg="our Jacobi vs libcosim, all 300 steps")
    # the default output update re-evaluates the feedthrough output and differs at O(h)
    prop = run(osc_scene(tmp_path, name="p.toml", stop=stop, step=h), write=False)
    assert np.max(np.abs(prop["b.force"][1:] - ref[:, 2])) > 1e-3
