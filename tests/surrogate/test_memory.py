"""Memory estimates of the mesoscale commands (tribocosim.surrogate.memory) against measured peaks, and the refusals.

A peak is measured in a fresh process: the command runs once on a small grid (imports, compiled kernels, FFTW
plans), then on the measured grid; the peak is the growth of the resident size's high-water mark over the resident
size just before that run, the mark reset there (Linux: ``/proc/self/clear_refs``, and ``VmHWM`` read instead of
``ru_maxrss``, which also holds the resident size of the forked test process it was exec'd from; elsewhere
``ru_maxrss``, and the run's peak must be the process's highest, which is checked). The estimate must hold it
(estimate >= measured) and not be more than 1.5 times it: the grids are counted from the code (the docstrings of
tribocosim.surrogate.memory list them), so a count that drifts from the code fails one side or the other.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from tribocosim.errors import MemoryLimitError, ParameterError
from tribocosim.surrogate import memory, meso_cli, slide_cli, surrogate_cli
from tribocosim.surrogate.slide_config import SlideConfig
from tribocosim.surrogate.surfaces import self_affine_surface

DATA = Path(__file__).parent / "data"
#: the estimate may be at most this many times the measured peak
FACTOR = 1.5

HARNESS = textwrap.dedent("""
    import json, os, resource, sys
    def rss():
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    def peak():  # the address space's high-water mark (ru_maxrss also holds the forked parent's, kept over exec)
        try:
            with open("/proc/self/status") as f:
                return next(int(l.split()[1]) for l in f if l.startswith("VmHWM:")) * 1024
        except (OSError, StopIteration):
            return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    {setup}
    run({small})
    try:  # Linux: reset the peak resident size to the current one (clear_refs 5), so that the run's is read
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
        reset = True
    except OSError:
        reset = False
    before, highest = rss(), peak()
    run({large})
    print(json.dumps({{"grown": peak() - before, "reset": reset, "highest_before": highest, "peak": peak()}}))
    """)

needs_proc = pytest.mark.skipif(not Path("/proc/self/statm").exists(), reason="resident size from /proc (Linux)")


def measured_peak(setup: str, small, large) -> int:
    """The growth of the peak resident size of ``run(large)`` in a fresh process (module docstring)."""
    code = HARNESS.format(setup=textwrap.dedent(setup), small=small, large=large)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert out["reset"] or out["peak"] > out["highest_before"], "the measured run must set the process's peak"
    return out["grown"]


def assert_holds(estimate: int, grown: int, what: str) -> None:
    assert grown <= estimate <= FACTOR * grown, (
        f"{what}: estimate {memory.format_bytes(estimate)}, measured {memory.format_bytes(grown)} "
        f"(ratio {estimate / grown:.3f}; allowed 1 to {FACTOR})")


@needs_proc
def test_the_surface_estimate_holds_a_generated_surface(tmp_path):
    n = 2048
    setup = f"""
        from tribocosim.surrogate import meso_cli
        def run(n):
            args = ["surface", "--n", str(n), "--size", "1e-4", "--q-roll", "1.3e5", "--q-cut", str(3.14159 * n / 1e-4),
                    "--rms-height", "1e-6", "-o", {str(tmp_path / 's.npy')!r}]
            assert meso_cli.main(args) == 0
        """
    assert_holds(memory.surface_bytes(n), measured_peak(setup, 64, n), f"meso surface --n {n}")


@needs_proc
def test_the_contact_estimate_holds_a_contact_solve(tmp_path):
    n = 1024
    for side in (32, n):
        np.save(tmp_path / f"s{side}.npy", self_affine_surface(side, 1e-4, 0.8, 1.3e5, np.pi * side / 1e-4,
                                                               rms_height=1e-6, seed=1))
    setup = f"""
        from tribocosim.surrogate import meso_cli
        def run(n):
            args = ["contact", "--surface", {str(tmp_path)!r} + f"/s{{n}}.npy", "--size", "1e-4", "--e-star", "55e9",
                    "--pressure", "10e6", "--p-crit", "340e6", "--json"]
            assert meso_cli.main(args) == 0
        """
    assert_holds(memory.contact_bytes(n), measured_peak(setup, 32, n), f"meso contact on {n}^2")


@needs_proc
def test_the_slide_estimate_holds_a_slide_with_overdamped_flakes():
    n = 1024
    config = dict(size=n * 1e-6, n_flakes=16, n_slide_steps=2, flake_solver="overdamped", v0=0.08,
                  wavelength_ratio=0.02)
    setup = f"""
        import warnings
        warnings.simplefilter("ignore")
        from tribocosim.surrogate.coupling import run_slide
        from tribocosim.surrogate.slide_config import SlideConfig
        def run(n):
            run_slide(SlideConfig(n=n, **{{**{config!r}, "size": n * 1e-6, "wavelength_ratio": max(0.02, 4 / n),
                                           "n_flakes": 16 if n > 64 else 1}}))
        """
    estimate = memory.slide_bytes(SlideConfig(n=n, **config)) - memory.SLIDE_CODE_BYTES  # the code is loaded
    assert_holds(estimate, measured_peak(setup, 64, n), f"a slide on {n}^2")


@needs_proc
def test_the_table_estimate_holds_the_surface_statistics():
    n = 2048
    setup = """
        from tribocosim.surrogate.table_build import surface_statistics
        def run(n):
            surface_statistics({"n": n, "size": n * 1e-6, "wavelength_ratio": max(0.02, 4 / n)},
                               [{"sheet_seed": 1, "tool_seed": 2}])
        """
    assert_holds(memory.table_bytes(n), measured_peak(setup, 64, n), f"a table build's statistics on {n}^2")


@needs_proc
@pytest.mark.parametrize("scan, n", [(256, 1000), (2048, 128)], ids=["grid-dominated", "scan-dominated"])
def test_the_measured_estimates_hold_a_scan_made_periodic(tmp_path, scan, n):
    """A scan upsampled to a finer grid (the grids dominate: the periodic-plus-smooth decomposition, then
    SurfaceTopography's statistics of the result in ``meso surface --from``) and a large scan on a coarse grid (the
    reading dominates)."""
    pytest.importorskip("SurfaceTopography")
    from tribocosim.surrogate import measured_surfaces as ms

    pixel = 4e-6 if scan < n else 1e-6
    heights = self_affine_surface(scan, scan * pixel, 0.8, 2e4, np.pi / pixel / 2, rms_height=1e-6, seed=3)
    for side in (32, scan):
        ms.write_x3p(heights[:side, :side], side * pixel, tmp_path / f"scan{side}.x3p", periodic=False)
    size = (scan - 1) * pixel * 0.999
    prepare = f"""
        from tribocosim.surrogate.measured_surfaces import prepared_heights
        def run(n):
            side = 32 if n < 100 else {scan}
            prepared_heights({str(tmp_path)!r} + f"/scan{{side}}.x3p", n, {size!r} * (side - 1) / ({scan} - 1))
        """
    assert_holds(memory.measured_bytes(n, scan * scan), measured_peak(prepare, 30, n),
                 f"a {scan}^2 scan prepared on {n}^2")
    if scan < n:
        command = f"""
            from tribocosim.surrogate import meso_cli
            def run(n):
                side = 32 if n < 100 else {scan}
                args = ["surface", "--from", {str(tmp_path)!r} + f"/scan{{side}}.x3p", "--n", str(n),
                        "--size", str({size!r} * (side - 1) / ({scan} - 1)), "-o", {str(tmp_path / 'm.npy')!r}]
                assert meso_cli.main(args) == 0
            """
        assert_holds(memory.measured_surface_bytes(n, scan * scan), measured_peak(command, 30, n),
                     f"meso surface --from a {scan}^2 scan --n {n}")


def test_a_60000_grid_is_refused_before_it_allocates(tmp_path):
    """The issue's command: one line, exit 2, the size and the estimate named; run under an address-space limit of
    4 GiB, so that a command that allocated first would fail otherwise instead of filling the machine."""
    out = tmp_path / "big"

    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (4 * 2**30, 4 * 2**30))

    proc = subprocess.run([sys.executable, "-m", "tribocosim.cli", "meso", "surface", "--n", "60000", "--size",
                           "64e-6", "--q-roll", "1e5", "--q-cut", "1e6", "--rms-height", "1e-6", "-o", str(out)],
                          capture_output=True, text=True, timeout=300, preexec_fn=limit,
                          env={**os.environ, "PYTHONWARNINGS": "ignore"})
    err = proc.stderr.strip()
    assert proc.returncode == 2, err
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert "--n 60000 needs about 181 GiB" in err and "6 arrays of 60000 x 60000 float64 values" in err, err
    assert not any(tmp_path.iterdir()), "nothing is written"


def test_max_memory_refuses_each_command_with_its_size(tmp_path, capsys):
    np.save(tmp_path / "s.npy", np.zeros((64, 64)))
    cases = [
        (meso_cli.main, ["surface", "--n", "64", "--size", "1e-4", "--q-roll", "1e5", "--q-cut", "1e6",
                         "--rms-height", "1e-6", "-o", str(tmp_path / "o"), "--max-memory", "1M"], "--n 64 needs"),
        (meso_cli.main, ["contact", "--surface", str(tmp_path / "s.npy"), "--size", "1e-4", "--e-star", "55e9",
                         "--pressure", "1e6", "--pressure", "2e6", "--max-memory", "1M"],
         f"({64} x {64} points) needs about {memory.format_bytes(memory.contact_bytes(64, 2))}"),
    ]
    config = tmp_path / "slide.toml"
    config.write_text("n = 64\nsize = 64e-6\nwavelength_ratio = 0.0625\nn_flakes = 2\n")
    cases.append((slide_cli.main, ["--config", str(config), "--out", str(tmp_path / "slide"), "--max-memory", "100M"],
                  f"n = 64 ({config}) needs about {memory.format_bytes(memory.slide_bytes(SlideConfig.from_toml(config)))}"))
    for main, argv, words in cases:
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and words in err and "(--max-memory)" in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.npy", "slide.toml"], "nothing is written"


def test_a_campaign_counts_its_workers_together(tmp_path, capsys):
    sweep = DATA / "tiny_sweep.toml"
    case = memory.slide_bytes(SlideConfig(n=16, size=64e-6, wavelength_ratio=0.25, n_slide_steps=4))
    between = str(int(1.5 * case))  # one worker's case fits, two do not
    argv = ["build", "--sweep", str(sweep), "--out", str(tmp_path / "o"), "--max-memory", between, "--quiet"]
    assert surrogate_cli.main([*argv, "--workers", "2"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert f"2 worker(s) x a case of n = 16 (sweep tiny) needs about {memory.format_bytes(2 * case)}" in err, err
    assert not (tmp_path / "o").exists(), "no case is run"

    from tribocosim.surrogate.executors import ProcessPoolCaseExecutor

    configs = [SlideConfig(n=16, size=64e-6, wavelength_ratio=0.25, n_slide_steps=4)]
    surrogate_cli._check_campaign_memory(configs, 24, "tiny", ProcessPoolCaseExecutor(1), int(between))
    with pytest.raises(MemoryLimitError, match="2 worker"):
        surrogate_cli._check_campaign_memory(configs, 24, "tiny", ProcessPoolCaseExecutor(2), int(between))
    # one case to run takes one worker, whatever --workers says
    surrogate_cli._check_campaign_memory(configs, 1, "tiny", ProcessPoolCaseExecutor(2), int(between))


def test_the_table_build_and_verify_refuse_beyond_max_memory(tmp_path, capsys):
    from tribocosim.paths import DEFAULT_TABLE

    assert surrogate_cli.main(["verify", str(DEFAULT_TABLE), "--workers", "2", "--max-memory", "300M"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "2 worker(s) x a case of n = 256" in err, err
    out = tmp_path / "o"
    (out / "cases").mkdir(parents=True)
    (out / "campaign.json").write_text(json.dumps({"sweep": {"slide": {"n": 512, "size": 5e-4}, "surfaces": [
        {"sheet_seed": 1, "tool_seed": 2}]}, "cases": []}))
    assert surrogate_cli.main(["table", "--out", str(out), "--max-memory", "10M"]) == 2
    err = capsys.readouterr().err.strip()
    assert "the table build's surface statistics on the n = 512 grid needs about" in err, err


def test_max_memory_sizes_and_the_memory_available(tmp_path):
    assert memory.parse_bytes("8G") == 8 * 2**30 and memory.parse_bytes("512MiB") == 512 * 2**20
    assert memory.parse_bytes("1.5GB") == int(1.5 * 2**30) and memory.parse_bytes("1000000") == 1000000
    for bad in ("lots", "-1G", "0", "1X", ""):
        with pytest.raises(ParameterError, match="--max-memory"):
            memory.parse_bytes(bad)
    meminfo = tmp_path / "meminfo"
    meminfo.write_text("MemTotal:       1000 kB\nMemFree:         10 kB\nMemAvailable:     600 kB\n")
    assert memory.available(str(meminfo)) == (600 * 1024, f"{meminfo}: MemAvailable")
    size, source = memory.available(str(tmp_path / "absent"))  # the portable fallback
    assert (size is None and source == "") or (size > 0 and "sysconf" in source)
