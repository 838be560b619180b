"""Fixtures shared by every test folder."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import pytest

_LIBCOSIM = textwrap.dedent(
    """
    import json, sys
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.WARNING)
    fmu, step_ns, names, rows, reals, integers = sys.argv[1], int(sys.argv[2]), *map(json.loads, sys.argv[3:])
    ex = CosimExecution.from_step_size(step_size=step_ns)  # integer nanoseconds
    idx = ex.add_local_slave(local_slave=CosimLocalSlave(fmu_path=fmu, instance_name="fmu"))
    vr = {v.name.decode(): v.reference for v in ex.slave_variables(idx)}
    observer = CosimObserver.create_last_value()
    ex.add_observer(observer=observer)
    override = CosimManipulator.create_override()
    ex.add_manipulator(manipulator=override)
    out = []
    for values in rows:
        override.slave_real_values(idx, [vr[n] for n in names], values)
        assert ex.step(1), "libcosim step failed"
        row = list(observer.last_real_values(idx, [vr[n] for n in reals]))
        row += [float(x) for x in observer.last_integer_values(idx, [vr[n] for n in integers])] if integers else []
        out.append(row)
    print(json.dumps(out))
    """
)


@pytest.fixture
def libcosim_run(tmp_path):
    """``run(fmu, step_ns, input_names, input_rows, real_outputs, integer_outputs=()) -> rows``: the FMU stepped
    by libcosim (OSP's C++ co-simulation library, through libcosimpy) in a subprocess, one input row per step;
    each row holds the Real outputs, then the Integer ones."""

    def run(fmu, step_ns, names, rows, reals, integers=()):
        script = tmp_path / "run_libcosim.py"
        script.write_text(_LIBCOSIM)
        proc = subprocess.run([sys.executable, str(script), str(fmu), str(step_ns), *(json.dumps(list(x)) for x in (
            names, [list(r) for r in rows], reals, integers))], cwd=tmp_path, capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, f"libcosimpy run failed (exit {proc.returncode}):\n{proc.stdout}\n{proc.stderr}"
        return json.loads(proc.stdout.strip().splitlines()[-1])

    return run
