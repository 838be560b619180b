"""Cost of the StripDraw FMU against calling the strip-draw model directly.

Measures, for the default parameters (table friction, implicit integrator, 150 elements):

0. the FMU: per-step cost of ``setReal + doStep + getReal`` through fmpy, and the default 140 mm draw
   at 1 ms steps in the C host of tests/native/host (a process with no Python): wall time of the stepping
   loop, per-step cost and real-time factor (target >= 500), and the same draw on other meshes (MESHES:
   the step's cost grows with the bar's nodes);

1. overhead per doStep: ``setReal(inputs) + doStep + getReal(outputs)`` through fmpy's
   ``FMU2Slave`` against ``model.step`` (both in this process, in the sliding regime);
2. the default 140 mm draw at V0 = 0.08 m/s (1.75 s) with a 1 ms communication step:
   ``fmpy.simulate_fmu`` on the extracted FMU against a plain loop over ``model.step`` that
   records the same outputs (the model is the native core: the ratio is fmpy's and the FMI layer's cost).
3. cold start in a fresh process (``--cold``): ``fmpy simulate StripDraw.fmu`` from the command
   line (extraction, imports, loading the FMU's library) against a fresh process
   that imports the model and runs the same draw.

    python benchmarks/bench_fmu.py [--fmu PATH] [--repeat 5] [--cold]

Without ``--fmu`` the FMU is built into a temporary folder first. Times are wall-clock minima
over ``--repeat`` runs (the machine may be shared: report the load with the figures).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

PROJECT_ROOT = Path(__file__).resolve().parents[1]
F10 = 10e6 * 0.035 * 0.035  # N: 10 MPa on the 35 x 35 mm pad (the FMU's default input)
V0 = 0.08  # m/s
DT = 1e-3  # s, communication step
N_DRAW = 1750  # steps: 140 mm at 0.08 m/s


def _model():
    from tribocosim.components.stripdraw import StripDrawModel, StripDrawParameters, make_friction_law, read_table

    params = StripDrawParameters()
    return StripDrawModel(params, make_friction_law(params, read_table(PROJECT_ROOT / "models" / "friction_table.npz")))


def _slave(unzipped: str, md):
    from fmpy.fmi2 import FMU2Slave

    slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier="StripDraw", instanceName="bench")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    return slave


def per_step(unzipped: str, md, n_warm: int, n: int, repeat: int) -> tuple[float, float]:
    """Seconds per step: (model.step, FMU set+doStep+get), minimum over ``repeat`` runs."""
    from tribocosim.components.stripdraw.model import OUTPUT_NAMES

    names = {v.name: v.valueReference for v in md.modelVariables}
    real_vrs = [names[n_] for n_ in OUTPUT_NAMES if n_ != "table_clamp_count"]
    in_vrs = [names["normal_force"], names["grip_velocity"]]
    t_model, t_fmu = [], []
    for _ in range(repeat):
        model = _model()
        inputs = {"normal_force": F10, "grip_velocity": V0}
        for _k in range(n_warm):
            model.step(DT, inputs)
        t0 = time.perf_counter()
        for _k in range(n):
            model.step(DT, inputs)
        t_model.append((time.perf_counter() - t0) / n)

        slave = _slave(unzipped, md)
        for k in range(n_warm):
            slave.setReal(in_vrs, [F10, V0])
            slave.doStep(k * DT, DT)
        t0 = time.perf_counter()
        for k in range(n_warm, n_warm + n):
            slave.setReal(in_vrs, [F10, V0])
            slave.doStep(k * DT, DT)
            slave.getReal(real_vrs)
            slave.getInteger([names["table_clamp_count"]])
        t_fmu.append((time.perf_counter() - t0) / n)
        slave.terminate()
        slave.freeInstance()
    return min(t_model), min(t_fmu)


def full_draw(unzipped: str, md, repeat: int) -> tuple[float, float, float]:
    """Wall time of the default draw: (model loop, fmpy.simulate_fmu), and the largest relative
    difference of pull_force between the two."""
    from fmpy import simulate_fmu

    from tribocosim.components.stripdraw.model import OUTPUT_NAMES

    t_model, t_fmu = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        model = _model()
        rec = np.empty((N_DRAW + 1, len(OUTPUT_NAMES) + 1))
        rec[0] = 0.0
        inputs = {"normal_force": F10, "grip_velocity": V0}
        for k in range(N_DRAW):
            out = model.step(DT, inputs)
            rec[k + 1, 0] = (k + 1) * DT
            rec[k + 1, 1:] = [out[n] for n in OUTPUT_NAMES]
        t_model.append(time.perf_counter() - t0)

        t0 = time.perf_counter()
        res = simulate_fmu(
            unzipped, model_description=md, stop_time=N_DRAW * DT, output_interval=DT, output=list(OUTPUT_NAMES)
        )
        t_fmu.append(time.perf_counter() - t0)
    j = 1 + OUTPUT_NAMES.index("pull_force")
    diff = np.max(np.abs(res["pull_force"][1:] - rec[1:, j]) / np.abs(rec[1:, j]))
    return min(t_model), min(t_fmu), float(diff)


_COLD_MODEL = """
import time; t0 = time.perf_counter()
from pathlib import Path
from tribocosim.components.stripdraw import StripDrawModel, StripDrawParameters, make_friction_law, read_table
p = StripDrawParameters()
m = StripDrawModel(p, make_friction_law(p, read_table(Path({root!r}) / "models" / "friction_table.npz")))
for k in range({n}):
    m.step({dt}, {{"normal_force": {f}, "grip_velocity": {v}}})
"""


def cold(fmu: Path, tmp: Path) -> tuple[float, float, float]:
    """Fresh-process wall times: (model script, `fmpy simulate` first run, second run on a
    pre-extracted FMU)."""
    fmpy_exe = str(Path(sys.executable).with_name("fmpy"))
    script = _COLD_MODEL.format(root=str(PROJECT_ROOT), n=N_DRAW, dt=DT, f=F10, v=V0)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", script], check=True, cwd=PROJECT_ROOT)
    t_model = time.perf_counter() - t0
    out = tmp / "cold.csv"
    t0 = time.perf_counter()
    subprocess.run([fmpy_exe, "simulate", str(fmu), "--output-file", str(out)], check=True, cwd=tmp)
    t_fmu = time.perf_counter() - t0
    from fmpy import extract

    unzipped = str(extract(str(fmu), str(tmp / "cold_unzipped")))
    runner = f"from fmpy import simulate_fmu; simulate_fmu({unzipped!r})"
    subprocess.run([sys.executable, "-c", runner], check=True, cwd=tmp)  # a first run
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", runner], check=True, cwd=tmp)
    t_warm_cache = time.perf_counter() - t0
    return t_model, t_fmu, t_warm_cache


def host_command(tmp: Path, unzipped: str, md, steps: int) -> list[str]:
    """The C host of tests/native/host (compiled into ``tmp``) running the default draw (``steps`` steps of 1 ms at
    10 MPa and 0.08 m/s) on the extracted StripDraw FMU, without printing: the command line."""
    from tribocosim.components.fmus.native_build import fmi2_headers
    from tribocosim.components.native.toolchain.compiler import compile_executable

    host = compile_executable([PROJECT_ROOT / "tests" / "native" / "host" / "fmi2_host.c"], tmp / "fmi2_host",
                              include_dirs=[fmi2_headers()], libs=["-ldl"])
    schedule = tmp / "draw.txt"
    schedule.write_text("".join(f"{DT!r},{F10!r},{V0!r}\n" for _ in range(steps)))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    return [str(host), unzipped, "StripDraw", md.guid, "--inputs", f"{vr['normal_force']},{vr['grip_velocity']}",
            "--outputs", f"r:{vr['pull_force']},r:{vr['mu_mean']},r:{vr['beta_max']}", "--steps", str(schedule),
            "--no-print"]


#: n_elements of the C host's mesh-scaling line (the default's is the main figure)
MESHES = (100, 450, 900)


def native(tmp: Path, fmu: Path, repeat: int, steps: int) -> dict:
    """The FMU's figures (see the module docstring, item 0)."""
    from fmpy import extract, read_model_description

    md = read_model_description(str(fmu))
    unzipped = str(extract(str(fmu), str(tmp / "native_unzipped")))
    _, t_native = per_step(unzipped, md, n_warm=200, n=steps, repeat=repeat)
    cmd = host_command(tmp, unzipped, md, N_DRAW)
    vr = {v.name: v.valueReference for v in md.modelVariables}

    def host_loop(extra=()):
        best = float("inf")
        for _ in range(repeat):
            proc = subprocess.run(cmd + list(extra), capture_output=True, text=True, check=True,
                                  env={"PATH": "/usr/bin:/bin"})
            line = [ln for ln in proc.stderr.splitlines() if " steps in " in ln][-1]
            best = min(best, float(line.split()[-2]))
        return best

    loop = host_loop()
    # the same draw on other meshes: the step's cost per node
    meshes = {n: host_loop(["--set", f"i:{vr['n_elements']}={n}"]) for n in MESHES}
    t0 = time.perf_counter()
    from fmpy import simulate_fmu

    simulate_fmu(unzipped, model_description=md, stop_time=N_DRAW * DT, output_interval=DT)
    return {"fmpy_native": t_native, "host_loop": loop, "host_meshes": meshes,
            "simulate_fmu_native": time.perf_counter() - t0}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--fmu", type=Path, help="a built StripDraw.fmu (default: build one)")
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--steps", type=int, default=1000, help="steps timed for the per-step figure")
    parser.add_argument("--cold", action="store_true", help="also time fresh processes")
    args = parser.parse_args(argv)
    from fmpy import extract, read_model_description

    with tempfile.TemporaryDirectory(prefix="bench-fmu-") as tmp:
        tmp = Path(tmp)
        fmu = args.fmu
        if fmu is None:
            from tribocosim.components.fmus.native_build import build_native_fmus

            fmu = build_native_fmus(tmp / "fmus", names=["StripDraw"], platforms=["linux64"])["StripDraw"]
        md = read_model_description(str(fmu))
        unzipped = str(extract(str(fmu), str(tmp / "unzipped")))
        _model().step(DT, {"normal_force": F10, "grip_velocity": V0})  # load the core library

        load = os.getloadavg()
        print(f"StripDraw FMU benchmark ({fmu}); load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}, "
              f"{os.cpu_count()} CPUs")  # fmt: skip
        nat = native(tmp, Path(fmu), args.repeat, args.steps)
        print(f"native FMU   fmpy set+doStep+get {nat['fmpy_native'] * 1e6:8.1f} us/step")
        rtf = N_DRAW * DT / nat["host_loop"]
        print(f"native FMU   140 mm draw at 1 ms in the C host (no Python): {nat['host_loop'] * 1e3:8.2f} ms, "
              f"{nat['host_loop'] / N_DRAW * 1e6:6.2f} us/step, real-time factor {rtf:.0f} "
              f"({'meets' if rtf >= 500 else 'MISSES'} the 500 target); fmpy.simulate_fmu {nat['simulate_fmu_native']:.3f} s")
        print("             the same draw in the C host on other meshes: " + ", ".join(
            f"{n} elements {t / N_DRAW * 1e6:.2f} us/step (real-time factor {N_DRAW * DT / t:.0f})"
            for n, t in nat["host_meshes"].items()))
        tm, tf = per_step(unzipped, md, n_warm=200, n=args.steps, repeat=args.repeat)
        print(f"per step     model.step {tm * 1e6:8.1f} us   FMU set+doStep+get {tf * 1e6:8.1f} us   "
              f"overhead {(tf - tm) * 1e6:6.1f} us ({tf / tm:.2f}x)")  # fmt: skip
        dm, df, diff = full_draw(unzipped, md, repeat=args.repeat)
        print(f"140 mm draw  model loop {dm:8.3f} s    fmpy.simulate_fmu  {df:8.3f} s    "
              f"ratio {df / dm:.2f}; max rel. diff of pull_force {diff:.1e}")  # fmt: skip
        if args.cold:
            cm, cf, cw = cold(Path(fmu), tmp)
            print(f"fresh process  model script {cm:6.2f} s   `fmpy simulate` {cf:6.2f} s   "
                  f"simulate_fmu on a pre-extracted FMU, second run {cw:6.2f} s")  # fmt: skip
        load = os.getloadavg()
        print(f"load average after: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
