"""Master overhead per FMU per macro step: cosim vs fmpy's simulate_fmu loop vs libcosim.

A trivial pythonfmu FMU (one input u, one output y = x + u, x' = 1 integrated exactly) is built
twice (with and without ``--handle-state``) into a temporary folder. N instances are chained
(y_i -> u_{i+1}) and run with a fixed step on

- cosim (this project): Jacobi, extrapolation 0, one recorded output per FMU; FMUs without state
  support (no per-step snapshot) and with it (a snapshot every step, for discard recovery);
- fmpy.simulate_fmu (N = 1 only: it runs a single FMU), recording y;
- libcosimpy (libcosim's C++ fixed-step loop), N chained FMUs, ``execution.step(n)``;
- a bare Python loop calling the FMI functions directly (set u, doStep, get y): the floor for
  any Python master on these FMUs.

For cosim the time spent inside FMI calls is measured separately, so the master's own overhead
(total minus FMU time) is reported too. Every figure is wall time per FMU per macro step, the
median of ``--repeat`` runs. Python FMUs are slow to call (each FMI call enters the Python
interpreter), so the absolute numbers are dominated by the FMU; the overhead columns are what
compares the masters.

Usage: ``python benchmarks/bench_master.py [--steps 20000] [--repeat 3]``.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

TRIVIAL = textwrap.dedent('''
    from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real
    from pythonfmu.enums import Fmi2Initial


    class BenchTrivial(Fmi2Slave):
        """y = x + u with x' = 1 (the cheapest FMU that still has state, input and output)."""

        def __init__(self, **kwargs):
            super().__init__(**kwargs)
            self.u = 0.0
            self.x = 0.0
            self.register_variable(Real("u", causality=Fmi2Causality.input, start=0.0))
            self.register_variable(Real("y", causality=Fmi2Causality.output, variability=Fmi2Variability.continuous,
                                        initial=Fmi2Initial.exact, start=0.0, getter=lambda: self.x + self.u))

        def do_step(self, t, h):
            self.x += h
            return True

        def _get_fmu_state(self):
            return {"x": self.x, "u": self.u}

        def _set_fmu_state(self, s):
            self.x, self.u = s["x"], s["u"]
''')


def build(folder: Path) -> dict[str, Path]:
    script = folder / "BenchTrivial.py"
    script.write_text(TRIVIAL)
    out = {}
    for kind, flags in (("state", ["--handle-state"]), ("nostate", [])):
        dest = folder / kind
        dest.mkdir()
        subprocess.run([sys.executable, "-m", "pythonfmu", "build", "-f", str(script), "--dest", str(dest), *flags],
                       check=True, capture_output=True)
        out[kind] = dest / "BenchTrivial.fmu"
    return out


def scene(folder: Path, fmu: Path, n: int, steps: int, h: float) -> Path:
    lines = [f"[experiment]\nstop = {steps * h!r}\nstep = {h!r}\n", '[master]\nalgorithm = "jacobi"\n']
    for i in range(n):
        lines.append(f'[fmus.f{i}]\npath = "{fmu}"\n')
    for i in range(n - 1):
        lines.append(f'[[connections]]\nfrom = "f{i}.y"\nto = "f{i + 1}.u"\n')
    lines.append("[output]\nvariables = [" + ", ".join(f'"f{i}.y"' for i in range(n)) + "]\n")
    path = folder / f"bench_{fmu.parent.name}_{n}.toml"
    path.write_text("\n".join(lines))
    return path


def bench_cosim(folder, fmu, n, steps, h):
    from tribocosim.cosim import run

    res = run(scene(folder, fmu, n, steps, h), write=False)
    wt = res.metadata["wall_time"]
    total = wt["loop"]
    fmu_time = sum(wt["fmus"].values())
    per = n * steps
    return total / per, (total - fmu_time) / per


def bench_fmpy(fmu, steps, h):
    from fmpy import simulate_fmu

    def once(k):
        t0 = time.perf_counter()
        simulate_fmu(str(fmu), stop_time=k * h, output_interval=h, output=["y"], validate=False)
        return time.perf_counter() - t0

    return (once(steps) - once(10)) / (steps - 10)


def bench_libcosim(fmu, n, steps, h):
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.ERROR)
    ex = CosimExecution.from_step_size(int(round(h * 1e9)))
    idx = [ex.add_local_slave(CosimLocalSlave(str(fmu), f"f{i}")) for i in range(n)]
    refs = {v.name.decode(): v.reference for v in ex.slave_variables(idx[0])}
    for a, b in zip(idx, idx[1:]):
        ex.connect_real_variables(a, refs["y"], b, refs["u"])
    obs = CosimObserver.create_last_value()
    ex.add_observer(obs)
    ex.step(10)  # initialization and warm-up
    t0 = time.perf_counter()
    ok = ex.step(steps)
    dt = time.perf_counter() - t0
    assert ok
    return dt / (n * steps)


def bench_bare(fmu, steps, h):
    """Set u, doStep, get y through the loaded C functions: the floor for a Python master."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave, fmi2Real, fmi2ValueReference

    md = read_model_description(str(fmu))
    d = extract(str(fmu))
    try:
        f = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier, instanceName="b")
        f.instantiate()
        f.setupExperiment(startTime=0.0)
        f.enterInitializationMode()
        f.exitInitializationMode()
        vr = {v.name: v.valueReference for v in md.modelVariables}
        set_real, get_real, do_step = f.dll.fmi2SetReal, f.dll.fmi2GetReal, f.dll.fmi2DoStep
        vu, vy = (fmi2ValueReference * 1)(vr["u"]), (fmi2ValueReference * 1)(vr["y"])
        val = (fmi2Real * 1)()
        c = f.component
        t0 = time.perf_counter()
        for k in range(steps):
            set_real(c, vu, 1, val)
            do_step(c, k * h, h, 1)
            get_real(c, vy, 1, val)
        dt = time.perf_counter() - t0
        f.terminate()
        f.freeInstance()
    finally:
        shutil.rmtree(d, ignore_errors=True)
    return dt / steps


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--steps", type=int, default=20000, help="macro steps per run (N = 1; divided by N for chains)")
    p.add_argument("--repeat", type=int, default=3)
    args = p.parse_args(argv)
    h = 1e-3
    folder = Path(tempfile.mkdtemp(prefix="bench-master-"))
    try:
        fmus = build(folder)
        med = lambda f: statistics.median(f() for _ in range(args.repeat))  # noqa: E731
        print(f"# wall time per FMU per macro step [us], median of {args.repeat}; load: {os.getloadavg()}")
        print(f"# python {sys.version.split()[0]}, pythonfmu FMUs (every FMI call enters Python)")
        bare = med(lambda: bench_bare(fmus["nostate"], args.steps, h))
        print(f"bare Python loop (set u, doStep, get y), N=1          : {1e6 * bare:8.1f}")
        fm = med(lambda: bench_fmpy(fmus["nostate"], args.steps, h))
        print(f"fmpy.simulate_fmu, N=1                                : {1e6 * fm:8.1f}")
        for n in (1, 4):
            steps = args.steps // n
            lc = med(lambda: bench_libcosim(fmus["nostate"], n, steps, h))
            print(f"libcosimpy (C++ loop), N={n}                            : {1e6 * lc:8.1f}")
            for kind in ("nostate", "state"):
                runs = [bench_cosim(folder, fmus[kind], n, steps, h) for _ in range(args.repeat)]
                tot = statistics.median(r[0] for r in runs)
                own = statistics.median(r[1] for r in runs)
                label = "no rollback" if kind == "nostate" else "snapshot/step"
                print(f"cosim Jacobi, N={n}, {label:<13}: total {1e6 * tot:8.1f}, master overhead {1e6 * own:8.1f}")
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
