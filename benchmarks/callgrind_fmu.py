"""Instructions per step of the native StripDraw FMU in the C host, counted by callgrind (repeatable under load), and
where they go.

The wall-clock figure of ``bench_fmu.py`` depends on what else runs on the machine; the number of
instructions the host's stepping loop executes does not. This script builds the native FMU (linux64), the
C host of ``tests/native/host/fmi2_host.c``, and runs the default draw (140 mm at 0.08 m/s, 1 ms steps, the
FMU's default parameters and inputs: 10 MPa on the 35 x 35 mm pad, 150 elements) under ``valgrind --tool=callgrind``
with collection switched on only inside ``fmi2SetReal``, ``fmi2DoStep`` and ``fmi2GetReal``: the host loop's
work (set the inputs, step, get the outputs). Printed: total instructions collected and instructions per step.

Where they go (``--where``): the same draw on the FMU's library built with its symbol table (the same code; a shipped
library keeps only the fmi2 functions' names), split by the inclusive costs callgrind counts for the functions that
make each part of a step:

==================  =============================================================================================
integrator          ``tc_sd_galpha`` or ``tc_sd_galpha_avx`` (the implicit bar step: the free bar condensed, Newton on
                    the pad's window), ``tc_sd_explicit``, ``tc_sd_chain_factors``
friction lookup     ``tc_law_mu``, ``tc_law_beta_cap`` (the table's lookups for the friction limits and the cap)
debris transport    ``tc_sd_debris_interval`` without the cap's lookup (source, sink, upwind transport, cap)
state backup        ``tc_sd_backup``, ``tc_sd_restore`` (what makes a refused step leave the state unchanged)
bar bookkeeping     the rest of ``tc_stripdraw_step_poly``: contact weights, the step's grid and coupling intervals,
                    the interface settled, the finiteness checks
outputs             ``tc_stripdraw_outputs`` (friction force and the means under the pad)
FMI layer           the rest: ``fmi2SetReal``, ``fmi2DoStep``, ``fmi2GetReal`` around the model (input checks, range
                    warnings, the copies)
==================  =============================================================================================

With ``--meshes`` the split is counted on other meshes too and each part is fitted as a + b n (n nodes): the
instructions per node and per step that the part costs.

``--baseline-rev REV`` (a git revision, e.g. ``2a6e61a``) or ``--baseline-fmu PATH`` counts the same draw on an
FMU of another revision (built from ``git archive REV`` in a temporary folder by that revision's own toolchain:
nothing is written into the checkout) and prints the ratio.

    python benchmarks/callgrind_fmu.py [--steps 1750] [--n-elements N] [--where] [--meshes 100 450]
                                       [--baseline-rev 2a6e61a] [--keep FILE]

Needs valgrind on the PATH. The count is the same from run to run up to a few instructions per step. It is the count
of the variant the processor runs: on one with AVX (valgrind reports it as the processor does) the bar's per-step
kernels and its implicit step are those compiled for it (components/native/core/tc_step_kernels_avx.c), which execute fewer
instructions than the baseline's for the same numbers; the script prints which ran.
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_fmu import N_DRAW, host_command, kernels_variant, revision_fmu  # noqa: E402 (the same host, draw, build)

#: the parts of a step and the functions whose inclusive costs make them (see the module docstring)
PARTS = {
    "integrator": ("tc_sd_galpha", "tc_sd_galpha_avx", "tc_sd_explicit", "tc_sd_chain_factors"),
    "friction lookup": ("tc_law_mu", "tc_law_beta_cap"),
    "debris transport": ("tc_sd_debris_interval",),
    "state backup": ("tc_sd_backup", "tc_sd_restore"),
}
STEP, OUTPUTS = "tc_stripdraw_step_poly", "tc_stripdraw_outputs"
COLLECT = ("fmi2SetReal", "fmi2DoStep", "fmi2GetReal")


def _callgrind(cmd: list[str], out: Path) -> int:
    """Run cmd under callgrind, collecting inside the host loop's fmi2 calls only; the total count."""
    if shutil.which("valgrind") is None:
        raise SystemExit("valgrind is not on the PATH")
    vg = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", "--collect-atstart=no",
          *(f"--toggle-collect={f}" for f in COLLECT)]
    proc = subprocess.run(vg + cmd, capture_output=True, text=True, env={"PATH": "/usr/bin:/bin"})
    if proc.returncode != 0:
        raise SystemExit(f"callgrind run failed:\n{proc.stderr[-2000:]}")
    match = re.search(r"^summary:\s+(\d+)", out.read_text(), re.MULTILINE)
    if match is None:
        raise SystemExit("no summary line in the callgrind output")
    return int(match.group(1))


def inclusive_costs(path: Path) -> Counter:
    """The inclusive cost of every function in a callgrind output file: its own cost lines and the costs of the calls
    it makes (the cost line after each ``calls=``), by function name (callgrind's name compression undone)."""
    names: dict[str, str] = {}
    costs: Counter = Counter()
    fn = None

    def name(spec: str) -> str:
        m = re.match(r"\((\d+)\)(?:\s+(.*))?", spec)
        if m is None:
            return spec
        if m.group(2):
            names[m.group(1)] = m.group(2)
        return names.get(m.group(1), spec)

    for line in path.read_text().splitlines():
        if line.startswith("fn="):
            fn = name(line[3:].strip())
        elif line.startswith("cfn="):
            name(line[4:].strip())
        elif line and (line[0].isdigit() or line[0] in "+-*") and fn is not None:
            parts = line.split()
            if len(parts) > 1:
                costs[fn] += int(parts[1])
    return costs


def split(costs: Counter, total: int) -> dict[str, int]:
    """The parts of a step (module docstring) from the inclusive costs."""
    parts = {part: sum(costs[f] for f in functions) for part, functions in PARTS.items()}
    parts["debris transport"] -= costs["tc_law_beta_cap"]  # the cap's lookup is the friction lookup's
    parts["bar bookkeeping"] = costs[STEP] - sum(parts.values())
    parts["outputs"] = costs[OUTPUTS]
    parts["FMI layer"] = total - costs[STEP] - costs[OUTPUTS]
    return parts


def _host(tmp: Path, fmu: Path, steps: int, n_elements: int | None, label: str) -> tuple[list[str], str]:
    """The host command of the draw on an FMU extracted into tmp/label; and the extracted folder."""
    from fmpy import extract, read_model_description

    md = read_model_description(str(fmu))
    unzipped = str(extract(str(fmu), str(tmp / label)))
    cmd = host_command(tmp, unzipped, md, steps)
    if n_elements is not None:
        vr = {v.name: v.valueReference for v in md.modelVariables}
        cmd += ["--set", f"i:{vr['n_elements']}={n_elements}"]
    return cmd, unzipped


def count(steps: int, n_elements: int | None, keep: Path | None = None, fmu: Path | None = None) -> tuple[int, float]:
    """(instructions collected in the host loop, per step) on ``fmu`` (default: this checkout's, built now); ``keep``:
    copy callgrind's output file there (for callgrind_annotate)."""
    from tribocosim.components.fmus.native_build import build_native_fmus

    with tempfile.TemporaryDirectory(prefix="tribocosim-callgrind-") as tmp_:
        tmp = Path(tmp_)
        if fmu is None:
            fmu = build_native_fmus(tmp / "native", names=["StripDraw"], platforms=["linux64"])["StripDraw"]
        cmd, _ = _host(tmp, Path(fmu), steps, n_elements, "unzipped")
        out = tmp / "callgrind.out"
        total = _callgrind(cmd, out)
        if keep is not None:
            shutil.copy2(out, keep)
    return total, total / steps


def symbol_library(unzipped: str, guid: str) -> None:
    """Replace the extracted FMU's linux64 library by the same sources compiled with their symbol table."""
    from tribocosim.components.fmus import native_build
    from tribocosim.components.native.toolchain import compiler, declarations

    comp = native_build.component("StripDraw")
    library = Path(unzipped) / native_build.binary_path("StripDraw", "linux64")
    with tempfile.TemporaryDirectory(prefix="tribocosim-symbols-") as tmp:
        include = Path(tmp)
        declarations.write_params_headers(include, [comp])
        (include / "tc_fmu_model.h").write_text(declarations.model_header(comp, guid), encoding="ascii")
        compiler.compile_shared(native_build.sources(comp), library, "linux64",
                                include_dirs=[include, native_build.fmi2_headers()], symbols=True)


def where(steps: int, n_elements: int | None) -> tuple[int, dict[str, int]]:
    """(total, the parts of a step summed over the draw) of this checkout's FMU on a mesh (see the module
    docstring)."""
    from fmpy import read_model_description

    from tribocosim.components.fmus.native_build import build_native_fmus

    with tempfile.TemporaryDirectory(prefix="tribocosim-callgrind-") as tmp_:
        tmp = Path(tmp_)
        fmu = build_native_fmus(tmp / "native", names=["StripDraw"], platforms=["linux64"])["StripDraw"]
        cmd, unzipped = _host(tmp, fmu, steps, n_elements, "unzipped")
        symbol_library(unzipped, read_model_description(str(fmu)).guid)
        out = tmp / "callgrind.out"
        total = _callgrind(cmd, out)
        return total, split(inclusive_costs(out), total)


def report_where(steps: int, meshes: list[int]) -> dict[int, dict[str, float]]:
    """Print the split per step (and per node when several meshes are counted); the split per step by mesh."""
    by_mesh = {}
    for n in meshes:
        total, parts = where(steps, n)
        by_mesh[n] = {"total": total / steps, **{k: v / steps for k, v in parts.items()}}
    default = meshes[0]
    row = by_mesh[default]
    print(f"where the instructions of a step go (callgrind inclusive costs; {default} elements, per step):")
    for part in (*PARTS, "bar bookkeeping", "outputs", "FMI layer"):
        line = f"  {part:17s} {row[part]:9.0f}  {100 * row[part] / row['total']:5.1f} %"
        if len(meshes) > 1:  # a + b n over the meshes (n = nodes)
            n = [m + 1 for m in meshes]
            y = [by_mesh[m][part] for m in meshes]
            b = (y[-1] - y[0]) / (n[-1] - n[0])
            a = y[0] - b * n[0]
            line += f"   = {a:8.0f} + {b:6.1f} per node"
        print(line)
    print(f"  {'total':17s} {row['total']:9.0f}")
    top = max((p for p in row if p != "total"), key=lambda p: row[p])
    print(f"the largest part: {top} ({100 * row[top] / row['total']:.0f} % of the step)")
    return by_mesh


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=N_DRAW)
    parser.add_argument("--n-elements", type=int, default=None, help="mesh (default: the FMU's default)")
    parser.add_argument("--keep", type=Path, default=None, help="copy callgrind's output file here")
    parser.add_argument("--where", action="store_true", help="split the step into its parts (symbol build)")
    parser.add_argument("--meshes", type=int, nargs="*", default=None,
                        help="with --where: further meshes (n_elements) for the per-node fit")
    base = parser.add_mutually_exclusive_group()
    base.add_argument("--baseline-rev", help="also count the FMU of this git revision (e.g. 2a6e61a)")
    base.add_argument("--baseline-fmu", type=Path, help="also count this StripDraw.fmu")
    args = parser.parse_args(argv)
    total, per = count(args.steps, args.n_elements, args.keep)
    print(f"callgrind, C host loop (fmi2SetReal + fmi2DoStep + fmi2GetReal), {args.steps} steps of the default draw, "
          f"the bar's per-step kernels as {kernels_variant()}: "
          f"{total} instructions, {per:.0f} per step")
    if args.baseline_rev or args.baseline_fmu:
        with tempfile.TemporaryDirectory(prefix="tribocosim-baseline-") as tmp:
            fmu = args.baseline_fmu or revision_fmu(args.baseline_rev, Path(tmp))
            b_total, b_per = count(args.steps, args.n_elements, None, fmu)
        label = args.baseline_rev or str(args.baseline_fmu)
        print(f"baseline {label}: {b_total} instructions, {b_per:.0f} per step; this checkout / baseline = "
              f"{per / b_per:.3f}")
    if args.where:
        report_where(args.steps, [args.n_elements or 150, *(args.meshes or [])])
    return 0


if __name__ == "__main__":
    sys.exit(main())
