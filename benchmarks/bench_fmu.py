"""Cost of the StripDraw FMU against calling the strip-draw model directly.

Measures, for the default parameters (table friction, implicit integrator, 150 elements):

0. the FMU: per-step cost of ``setReal + doStep + getReal`` through fmpy, and the default 140 mm draw
   at 1 ms steps in the C host of tests/native/host (a process with no Python): wall time of the stepping
   loop, per-step cost and real-time factor (target >= 500: <= 2.0 us per step), and the same draw on other meshes
   (MESHES: the step's cost grows with the bar's nodes); with ``--baseline-rev REV`` (or ``--baseline-fmu PATH``)
   the same draw on the FMU of another git revision, timed in turns with this one (best of ``--repeat`` each), and
   the ratio (target <= 0.75 against 2a6e61a's); then where the step's time goes (``benchmarks/callgrind_fmu.py``:
   callgrind's inclusive instruction counts of the parts of a step, integrator, friction lookup, debris transport,
   state backup, bar bookkeeping, outputs, FMI layer, per step and per node from two meshes; the time split is taken
   as the instruction split), what bounds the step, and the instructions it executes per nanosecond (the callgrind
   count over the best wall time);

1. overhead per doStep: ``setReal(inputs) + doStep + getReal(outputs)`` through fmpy's
   ``FMU2Slave`` against ``model.step`` (both in this process, in the sliding regime);
2. the default 140 mm draw at V0 = 0.08 m/s (1.75 s) with a 1 ms communication step:
   ``fmpy.simulate_fmu`` on the extracted FMU against a plain loop over ``model.step`` that
   records the same outputs (the model is the native core: the ratio is fmpy's and the FMI layer's cost).
3. cold start in a fresh process (``--cold``): ``fmpy simulate StripDraw.fmu`` from the command
   line (extraction, imports, loading the FMU's library) against a fresh process
   that imports the model and runs the same draw.

    python benchmarks/bench_fmu.py [--fmu PATH] [--repeat 5] [--cold] [--baseline-rev 2a6e61a] [--host-only]

Without ``--fmu`` the FMU is built into a temporary folder first; a baseline revision's FMU is built from
``git archive REV`` in a temporary folder by that revision's own toolchain (nothing is written into the checkout).
``--host-only`` times the C host alone (items 0 and the split; not the fmpy figures 1-3). Times are wall-clock minima
over ``--repeat`` runs (the machine may be shared: report the load with the figures).
"""

from __future__ import annotations

import argparse
import io
import os
import shutil
import subprocess
import sys
import tarfile
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


def kernels_variant() -> str:
    """Which per-step kernels of the bar (and implicit step) this processor runs, as the FMU chooses them
    (components/native/core/tc_cpu.h): the AVX variant or the SSE2 baseline; the same numbers either way."""
    from tribocosim.components.native.toolchain.library import core

    return "AVX (tc_step_kernels_avx.c)" if core().lib.tc_step_kernels_avx_chosen() else "the SSE2 baseline"


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
#: the targets of the default draw in the C host: at most this many seconds per step (a real-time factor of 500), and
#: at most this share of the baseline revision's step (issue 46: 2a6e61a's)
TARGET_STEP = 2.0e-6
TARGET_RATIO = 0.75

_BUILD_REVISION = """
import sys
from pathlib import Path
from tribocosim.components.fmus.native_build import build_native_fmus
print(build_native_fmus(Path(sys.argv[1]), names=["StripDraw"], platforms=["linux64"])["StripDraw"])
"""


def revision_fmu(rev: str, folder: Path) -> Path:
    """The StripDraw FMU (linux64) of git revision ``rev`` of this checkout, built in ``folder``: the revision's files
    (``git archive``) laid out as the package they install (tribocosim/ with its subpackages), built in a fresh
    process by that revision's own code. Nothing is written into the checkout."""
    folder = Path(folder)
    src, pkg = folder / "src", folder / "pkg"
    src.mkdir(parents=True)
    archive = subprocess.run(["git", "-C", str(PROJECT_ROOT), "archive", rev], capture_output=True)
    if archive.returncode != 0:
        raise SystemExit(f"git archive {rev}: {archive.stderr.decode(errors='replace').strip()}")
    with tarfile.open(fileobj=io.BytesIO(archive.stdout)) as tar:
        tar.extractall(src)
    shutil.copytree(src / "tribocosim", pkg / "tribocosim")
    for sub in ("components", "cosim", "surrogate", "models"):
        (pkg / "tribocosim" / sub).symlink_to(src / sub, target_is_directory=True)
    proc = subprocess.run([sys.executable, "-c", _BUILD_REVISION, str(folder / "fmu")], capture_output=True,
                          text=True, cwd=folder, env={**os.environ, "PYTHONPATH": str(pkg)})
    if proc.returncode != 0:
        raise SystemExit(f"building the StripDraw FMU of {rev} failed:\n{proc.stderr[-3000:]}")
    return Path(proc.stdout.strip().splitlines()[-1])


def host_times(tmp: Path, fmus: dict[str, Path], repeat: int, extra=()) -> dict[str, float]:
    """Wall time of the default draw's stepping loop in the C host for each FMU (label -> path), best of ``repeat``
    runs each, the FMUs taking turns (so that a change of the machine's load falls on all of them alike)."""
    from fmpy import extract, read_model_description

    cmds = {}
    for label, fmu in fmus.items():
        md = read_model_description(str(fmu))
        cmds[label] = host_command(tmp, str(extract(str(fmu), str(tmp / f"host_{label}"))), md, N_DRAW) + list(extra)
    best = dict.fromkeys(fmus, float("inf"))
    for _ in range(repeat):
        for label, cmd in cmds.items():
            proc = subprocess.run(cmd, capture_output=True, text=True, check=True, env={"PATH": "/usr/bin:/bin"})
            line = [ln for ln in proc.stderr.splitlines() if " steps in " in ln][-1]
            best[label] = min(best[label], float(line.split()[-2]))
    return best


def bounds_of_the_step(by_mesh: dict[int, dict[str, float]]) -> str:
    """What bounds the step, from the split of callgrind_fmu.report_where: the parts that grow with the mesh and the
    largest part at the default mesh."""
    meshes = sorted(by_mesh)
    row = by_mesh[meshes[0]] if 150 not in by_mesh else by_mesh[150]
    shares = sorted(((row[p] / row["total"], p) for p in row if p != "total"), reverse=True)
    text = (f"the step is bound by {shares[0][1]} ({100 * shares[0][0]:.0f} %) and {shares[1][1]} "
            f"({100 * shares[1][0]:.0f} %)")
    if len(meshes) > 1:
        n0, n1 = meshes[0] + 1, meshes[-1] + 1
        per_node = (by_mesh[meshes[-1]]["total"] - by_mesh[meshes[0]]["total"]) / (n1 - n0)
        grows = per_node * n0 / by_mesh[meshes[0]]["total"]
        text += (f"; {per_node:.0f} instructions per node of the bar ({100 * grows:.0f} % of the step at {meshes[0]} "
                 "elements grows with the mesh)")
    return text


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
    base = parser.add_mutually_exclusive_group()
    base.add_argument("--baseline-rev", help="also time the FMU of this git revision in the C host (e.g. 2a6e61a)")
    base.add_argument("--baseline-fmu", type=Path, help="also time this StripDraw.fmu in the C host")
    parser.add_argument("--host-only", action="store_true",
                        help="the C host's figures and the split only (not the fmpy figures)")
    parser.add_argument("--no-where", action="store_true", help="skip the callgrind split (valgrind not needed)")
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
              f"{os.cpu_count()} CPUs; the bar's per-step kernels run as {kernels_variant()}")  # fmt: skip
        fmus = {"this": Path(fmu)}
        label = args.baseline_rev or "baseline"
        if args.baseline_rev or args.baseline_fmu:
            fmus[label] = Path(args.baseline_fmu or revision_fmu(args.baseline_rev, tmp / "baseline"))
        times = host_times(tmp, fmus, args.repeat)
        step = times["this"] / N_DRAW
        line = (f"C host, 140 mm draw at 1 ms, 150 elements, best of {args.repeat}{' in turns' * (len(fmus) > 1)}: "
                f"this checkout {step * 1e6:.2f} us/step (real-time factor {DT / step:.0f}; target <= "
                f"{TARGET_STEP * 1e6:.1f} us/step {'met' if step <= TARGET_STEP else 'MISSED'})")
        if len(fmus) > 1:
            b_step = times[label] / N_DRAW
            met = "met" if step / b_step <= TARGET_RATIO else "MISSED"
            line += (f", {label} {b_step * 1e6:.2f} us/step (real-time factor {DT / b_step:.0f}); ratio "
                     f"{step / b_step:.3f} (target <= {TARGET_RATIO} {met})")
        print(line)
        if not args.no_where:
            if shutil.which("valgrind") is None:
                print("where the time goes: skipped (valgrind is not on the PATH)")
            else:
                import callgrind_fmu

                by_mesh = callgrind_fmu.report_where(N_DRAW, [150, 450])
                row = by_mesh[150]
                print("  in time, taking the time split as the instruction split: " + ", ".join(
                    f"{p} {step * 1e6 * row[p] / row['total']:.2f} us" for p in row if p != "total"))
                print("what bounds the step: " + bounds_of_the_step(by_mesh))
                # the rate at which the step executes its instructions: where it is steady, fewer instructions are
                # the only lever left (a step that waits on chains of dependent operations or on mispredicted
                # branches runs fewer per nanosecond)
                print(f"  the step executes {row['total'] / (step * 1e9):.1f} instructions per nanosecond "
                      f"({row['total']:.0f} per step in {step * 1e6:.2f} us)")
        if args.host_only:
            return 0
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
