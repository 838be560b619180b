"""The demo rig side by side: ``tribocosim run demo`` against ecos, libcosim and OMSimulator, whole process and loop.

The rig is the demo scene (press, strip draw, drawing machine: the native FMUs, 4,120 steps of 0.5 ms, Jacobi) and
its SSP package (``tribocosim ssp export demo``, the FMUs and the scene's parameter values as parameter sets). Every
host runs it in a fresh process, records the demo's 12 output variables at every step and ends on the same pull
force (printed):

- tribocosim: ``tribocosim run demo --quiet`` (writes the CSV and the metadata JSON); the loop is the metadata's
  ``wall_time.loop``, for the loop the run takes (``auto``: the C loop) and for the Python loop (the API's
  ``loop="python"``);
- ecos (ecospy): the package with its parameter set ``demo``, a CSV writer of the 12 variables, ``step(4120)``
  (the loop: that call); ecospy's library needs the tbb package's ``libtbb.so.12`` on ``LD_LIBRARY_PATH``;
- libcosim (libcosimpy): the package (its step from the OSP annotation), a time-series observer of the 12
  variables, ``step(4120)``;
- OMSimulator: its command line on the package, where an ``OMSimulator`` executable is on ``PATH`` (its pip
  package downloads a binary when it is built, which this machine cannot; it is then reported as not installed).

Each host runs ``--repeat`` rounds, each round one run of every host in turn, so that a load that changes while the
benchmark runs hits every host alike (after one warm-up run each, so that every library and the FMU cache are built
and Python's bytecode is cached: ``PYTHONDONTWRITEBYTECODE`` is cleared for the runs and the bytecode kept in the
cache folder). It prints the best and the median of the rounds, whole process and loop, and the ratios tribocosim /
host of both; the load average is printed with every round: figures taken while the machine computes something else
are slower by roughly the load over the core count. The target (issue 46, item 3): tribocosim's whole process at
most 1.0 times ecos's, best of the rounds, on a quiet machine.

``--instructions`` also counts the instructions of one whole process of each host with callgrind (valgrind): a figure
the load does not move, so it can be taken on a busy machine. ``--before`` adds another installation's console script
(e.g. a checkout of an earlier commit in its own venv) to the rounds, for before/after figures.

Usage: ``python benchmarks/bench_master.py [--repeat 10] [--instructions] [--before PATH]``.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

STEPS = 4120
STEP = 5e-4
VARIABLES = ["strip.pull_force", "strip.mu_mean", "strip.friction_force", "strip.sliding_distance",
             "strip.beta_mean", "strip.beta_max", "press.normal_force", "press.force_reference",
             "drive.grip_velocity", "drive.velocity_reference", "drive.grip_position", "drive.motor_force"]

ECOS = textwrap.dedent("""
    import sys, time
    from ecospy import EcosLib, EcosSimulation

    EcosLib().set_log_level("warn")
    rig, csv, steps, names = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4].split(",")
    with EcosSimulation(ssp_path=rig, step_size=float(sys.argv[5])) as sim:
        sim.add_csv_writer(csv, identifiers=[n.replace(".", "::") for n in names])
        sim.init(parameter_set="demo")
        t0 = time.perf_counter()
        sim.step(steps)
        loop = time.perf_counter() - t0
        force = sim.get_real("strip::pull_force")
        sim.terminate()
    print(f"{loop!r} {force!r}")
""")

LIBCOSIM = textwrap.dedent("""
    import sys, time
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.ERROR)
    rig, steps, names = sys.argv[1], int(sys.argv[2]), sys.argv[3].split(",")
    ex = CosimExecution.from_ssp_file(rig)
    obs = CosimObserver.create_time_series()
    ex.add_observer(obs)
    refs = {}
    for name in names:
        inst, var = name.split(".", 1)
        i = ex.slave_index_from_instance_name(inst)
        vr = {v.name.decode(): v.reference for v in ex.slave_variables(i)}[var]
        obs.start_time_series(i, vr, CosimVariableType.REAL)
        refs[name] = (i, vr)
    t0 = time.perf_counter()
    assert ex.step(steps)
    loop = time.perf_counter() - t0
    i, vr = refs["strip.pull_force"]
    times, numbers, values = obs.time_series_real_samples(i, vr, steps, 1)
    assert numbers == [steps], numbers
    print(f"{loop!r} {values[-1]!r}")
""")


def load() -> str:
    return "load {:.2f} {:.2f} {:.2f}".format(*os.getloadavg())


def tbb_library_dirs() -> list[str]:
    """The folders of the tbb package's libtbb.so.* (ecospy's library needs them on LD_LIBRARY_PATH)."""
    from importlib.metadata import PackageNotFoundError, files

    try:
        found = files("tbb") or ()
    except PackageNotFoundError:
        return []
    return sorted({str(Path(f.locate()).resolve().parent) for f in found if f.name.startswith("libtbb.so")})


def timed(cmd: list[str], env: dict, cwd: Path) -> tuple[float, str]:
    """(wall time of the process, its stdout); raises if it fails."""
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, env=env, cwd=cwd, capture_output=True, text=True, timeout=600)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed (exit {proc.returncode}):\n{proc.stdout}\n{proc.stderr}")
    return wall, proc.stdout


def interleaved(runners: dict, repeat: int) -> dict[str, dict]:
    """Run every ``once() -> (whole, loop, pull force)`` of ``runners`` once to warm up, then ``repeat`` rounds of one
    run each, host after host (a changing load then hits every host alike); print and return per host the best and
    the median of the whole process and of the loop, and the pull force."""
    for label, once in runners.items():
        print(f"# warm-up {label} ({load()})", flush=True)
        once()
    runs: dict[str, list] = {label: [] for label in runners}
    for r in range(repeat):
        print(f"# round {r + 1} of {repeat} ({load()})", flush=True)
        for label, once in runners.items():
            runs[label].append(once())
    out = {}
    print(f"{'':<28} {'whole process [s]':>22} {'loop [s]':>22}")
    print(f"{'':<28} {'best':>10} {'median':>11} {'best':>10} {'median':>11}")
    for label, rows in runs.items():
        whole, loop = [x[0] for x in rows], [x[1] for x in rows]
        figures = {"whole": (min(whole), statistics.median(whole)), "loop": (min(loop), statistics.median(loop)),
                   "force": rows[-1][2]}
        print(f"{label:<28} {figures['whole'][0]:10.4f} {figures['whole'][1]:11.4f} {figures['loop'][0]:10.4f} "
              f"{figures['loop'][1]:11.4f}   pull force {figures['force']:.6f} N", flush=True)
        out[label] = figures
    print(f"# after the last round: {load()}")
    return out


def instructions(cmd: list[str], env: dict, cwd: Path) -> int | None:
    """The instructions one run of ``cmd`` executes, counted by callgrind (None without valgrind)."""
    valgrind = shutil.which("valgrind")
    if valgrind is None:
        return None
    out = cwd / "callgrind.out"
    proc = subprocess.run([valgrind, "--tool=callgrind", f"--callgrind-out-file={out}", *cmd], env=env, cwd=cwd,
                          capture_output=True, text=True, timeout=3600)
    found = [line for line in proc.stderr.splitlines() if "Collected :" in line]
    out.unlink(missing_ok=True)
    if proc.returncode != 0 or not found:
        raise RuntimeError(f"callgrind of {' '.join(cmd)} failed (exit {proc.returncode}):\n{proc.stderr[-2000:]}")
    return int(found[-1].split()[-1])


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--repeat", type=int, default=10, help="timed runs per host (their best and median are printed)")
    p.add_argument("--instructions", action="store_true",
                   help="also count the instructions of one whole process of each host (callgrind: needs valgrind)")
    p.add_argument("--tribocosim", default=shutil.which("tribocosim") or "tribocosim",
                   help="the tribocosim console script to time (default: the one on PATH)")
    p.add_argument("--before", help="another installation's tribocosim console script (e.g. an earlier commit's, in "
                                    "its own venv), timed in the same rounds for before/after figures")
    args = p.parse_args(argv)
    work = Path(tempfile.mkdtemp(prefix="bench-master-"))
    cache = Path(os.environ.get("TRIBOCOSIM_CACHE", Path.home() / ".cache" / "tribocosim" / "fmus"))
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPYCACHEPREFIX"] = str(cache / "pycache")
    results = {}
    try:
        rig = work / "rig.ssp"
        subprocess.run([args.tribocosim, "ssp", "export", "demo", "-o", str(rig)], env=env, check=True,
                       capture_output=True)
        print(f"# demo rig: {STEPS} steps of {STEP} s, 3 native FMUs, {len(VARIABLES)} variables recorded; "
              f"{args.repeat} rounds; {os.cpu_count()} cores; python {sys.version.split()[0]}")
        print(f"# tribocosim: {args.tribocosim}")

        runners = {}
        commands = {}  # label -> (command, environment) of one whole process, for --instructions

        def ours(console: str, loop_kind: str):
            def once():
                out = work / f"out-{abs(hash((console, loop_kind)))}"
                if loop_kind == "auto":
                    wall, _ = timed([console, "run", "demo", "--quiet", "--out", str(out)], env, work)
                else:  # the Python loop, through the API (no command-line switch for it)
                    code = f"import sys; from tribocosim.cosim import run; run('demo', sys.argv[1], loop={loop_kind!r})"
                    wall, _ = timed([str(Path(console).with_name("python")), "-c", code, str(out)], env, work)
                meta = json.loads((out / "demo.json").read_text())
                with open(out / "demo.csv", encoding="utf-8") as f:
                    header = f.readline().replace('"', "").strip().split(",")
                    last = f.readlines()[-1].split(",")
                return wall, meta["wall_time"]["loop"], float(last[header.index("strip.pull_force")])
            return once

        runners["tribocosim"] = ours(args.tribocosim, "auto")
        commands["tribocosim"] = ([args.tribocosim, "run", "demo", "--quiet", "--out", str(work / "out-counted")], env)
        runners["tribocosim, Python loop"] = ours(args.tribocosim, "python")
        if args.before:
            runners["tribocosim before"] = ours(args.before, "auto")

        libs = tbb_library_dirs()
        if libs:
            ecos_script = work / "run_ecos.py"
            ecos_script.write_text(ECOS)
            ecos_env = {**env, "LD_LIBRARY_PATH": os.pathsep.join([*libs, env.get("LD_LIBRARY_PATH", "")])}

            ecos_cmd = [sys.executable, str(ecos_script), str(rig), str(work / "ecos.csv"), str(STEPS),
                        ",".join(VARIABLES), repr(STEP)]

            def ecos():
                wall, out = timed(ecos_cmd, ecos_env, work)
                loop, force = map(float, out.split())
                return wall, loop, force

            runners["ecos (ecospy)"] = ecos
            commands["ecos (ecospy)"] = (ecos_cmd, ecos_env)
        else:
            print("ecos: not measured (the tbb package, whose libtbb.so.12 ecospy loads, is not installed)")

        libcosim_script = work / "run_libcosim.py"
        libcosim_script.write_text(LIBCOSIM)

        libcosim_cmd = [sys.executable, str(libcosim_script), str(rig), str(STEPS), ",".join(VARIABLES)]

        def libcosim():
            wall, out = timed(libcosim_cmd, env, work)
            loop, force = map(float, out.split())
            return wall, loop, force

        runners["libcosim (libcosimpy)"] = libcosim
        commands["libcosim (libcosimpy)"] = (libcosim_cmd, env)

        oms = shutil.which("OMSimulator")
        if oms:
            def omsimulator():
                wall, _ = timed([oms, str(rig), f"--stopTime={STEPS * STEP!r}", "--resultFile=oms.csv"], env, work)
                return wall, float("nan"), float("nan")

            runners["OMSimulator (command line)"] = omsimulator
        else:
            print("OMSimulator: not measured (no OMSimulator executable on PATH)")
        results = interleaved(runners, args.repeat)
        counts = {label: instructions(cmd, cmd_env, work) for label, (cmd, cmd_env) in commands.items()} \
            if args.instructions else {}
    finally:
        shutil.rmtree(work, ignore_errors=True)

    ours = results["tribocosim"]
    hosts = {k: v for k, v in results.items() if not k.startswith("tribocosim")}
    if "tribocosim before" in results:
        before = results["tribocosim before"]
        print(f"# tribocosim before -> now, best: whole process {before['whole'][0]:.4f} -> {ours['whole'][0]:.4f} s "
              f"({before['whole'][0] / ours['whole'][0]:.2f}x), loop {before['loop'][0]:.4f} -> "
              f"{ours['loop'][0]:.4f} s")
    print(f"# ratios tribocosim / host, best of the rounds and median ({load()}):")
    for name, f in hosts.items():
        print(f"  {name:<28} whole process {ours['whole'][0] / f['whole'][0]:5.2f}x best, "
              f"{ours['whole'][1] / f['whole'][1]:5.2f}x median;   loop {ours['loop'][0] / f['loop'][0]:5.2f}x best, "
              f"{ours['loop'][1] / f['loop'][1]:5.2f}x median")
    if counts:
        print("# instructions of one whole process (callgrind; the load does not move them):")
        for name, n in counts.items():
            ratio = f"   tribocosim / it {counts['tribocosim'] / n:5.2f}x" if name != "tribocosim" and n else ""
            print(f"  {name:<28} {n / 1e6:9.1f} M{ratio}" if n is not None else f"  {name:<28} (no valgrind)")
    if "ecos (ecospy)" in hosts:
        ratio = ours["whole"][0] / hosts["ecos (ecospy)"]["whole"][0]
        print(f"# target (issue 46.3): tribocosim's whole process at most 1.0x ecos's, best of {args.repeat}: "
              f"{ratio:.2f}x ({'holds' if ratio <= 1.0 else 'does not hold'} in this run)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
