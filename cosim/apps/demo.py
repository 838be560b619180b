"""``tribocosim demo``: the strip-draw test as a co-simulation, with its figures and mu_bar.

The demo runs ``models/scenes/demo.toml`` (paper Sec. 2.1, 7): the press FMU holds F_N = 10 MPa on
the 35 x 35 mm pad, the drawing-machine FMU pulls at 0.08 m/s for 140 mm, the strip-draw FMU
(shipped friction table, implicit bar integrator) returns the pull force. The FMUs are built into
the FMU cache (:mod:`tribocosim.cosim.scene.fmucache`) when missing; a failed build stops the demo with the
builder's message. It writes the results (CSV + JSON), the strip's beta field (``field_output``)
and three figures: mu against sliding distance, the beta(X, t) map (like Fig. 17a), and the
press and drive signals; it prints mu_bar, the mean of mu(t) = pull_force / (2 F_N) (Eq. 1) over
the last 20 % of the draw, the steady-state region where the paper reads it (Sec. 7).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np


def demo_scene() -> Path:
    """The shipped demo scene, ``models/scenes/demo.toml`` (package data of ``tribocosim.models``)."""
    from tribocosim.paths import SCENES_DIR

    return SCENES_DIR / "demo.toml"


def ensure_fmus(components=None, echo=print) -> dict[str, Path]:
    """Find the components' FMUs in the cache, building the missing ones; ``{component: path}``
    (default: the components of the demo scene).

    Raises
    ------
    SceneError
        Saying which FMU could not be built and why (the builder's message).
    """
    from tribocosim.cosim.scene.fmucache import cache_dir, component_fmu
    from tribocosim.cosim.scene.schema import parse_scene

    if components is None:
        components = [s.component for s in parse_scene(demo_scene())[0].fmus.values() if s.component]
    found = {}
    for comp in components:
        before = set(cache_dir().glob("*/*.fmu")) if cache_dir().is_dir() else set()
        t0 = time.perf_counter()
        found[comp] = component_fmu(comp)
        if found[comp] not in before:
            echo(f"built {found[comp].name} into the FMU cache {cache_dir()} ({time.perf_counter() - t0:.1f} s)")
    return found


def strip_parameters(scene, instance: str = "strip"):
    """The StripDrawParameters of a scene's strip instance."""
    from tribocosim.components.stripdraw.component import COMPONENT

    return COMPONENT.split(scene.fmus[instance].parameters)[0]


def run_demo(out_dir, *, pressure: float | None = None, tool_length: float | None = None, overrides=None,
             plot: bool = True, field_interval: float = 0.01):
    """Run the demo scene; write the results and the figures into ``out_dir``.

    Returns ``(result, summary, figures)``: the :class:`tribocosim.cosim.api.Result`, a dict with mu_bar
    (Eq. 1 over the last 20 % of the draw), the strip's mean mu_mean over the same window, the
    press's largest relative set-point error and the drive's velocity error in steady state, and
    the figure files.
    """
    from tribocosim.cosim.api import run
    from tribocosim.cosim.studies.plotting import plot_demo
    from tribocosim.cosim.studies.steady_state import steady_ratio
    from tribocosim.cosim.scene.validate import load_scene

    out = Path(out_dir).resolve()
    out.mkdir(parents=True, exist_ok=True)
    field_file = out / "beta_field.csv"
    over = {"fmus.strip.parameters.field_output": str(field_file),
            "fmus.strip.parameters.field_output_interval": field_interval}
    if tool_length is not None:
        over["fmus.strip.parameters.tool_length"] = tool_length
    if pressure is not None or tool_length is not None:
        from tribocosim.cosim.scene.schema import parse_scene

        base, _ = parse_scene(demo_scene())
        p = pressure if pressure is not None else strip_parameters(base).pressure(
            base.fmus["press"].parameters["force_setpoint"])
        over["fmus.press.parameters.force_setpoint"] = strip_parameters(parse_scene(demo_scene(), over)[0]).normal_force(p)
    over.update(overrides or {})
    plan = load_scene(demo_scene(), over)
    result = run(plan, out)
    t = result.time
    steady = t >= t[-1] - 0.2 * (t[-1] - t[0])
    fn, fset = result["press.normal_force"], result["press.force_reference"]
    vg, vset = result["drive.grip_velocity"], result["drive.velocity_reference"]
    summary = {
        "mu_bar": steady_ratio(t, result["strip.pull_force"], fn),
        "mu_mean_strip": float(np.mean(result["strip.mu_mean"][steady])),
        "press_error": float(np.max(np.abs(fn[steady] - fset[steady]) / fset[steady])),
        "velocity_error": float(np.max(np.abs(vg[steady] - vset[steady]) / np.abs(vset[steady]))),
        "pressure": float(strip_parameters(plan.scene).pressure(fset[-1])),
        "sliding_distance": float(result["strip.sliding_distance"][-1]),
        "beta_mean_end": float(result["strip.beta_mean"][-1]),
        "field_file": str(field_file),
    }
    figures = plot_demo(result, field_file, out, summary["mu_bar"]) if plot else []
    return result, summary, figures


def main(argv: list[str] | None = None) -> int:
    """``tribocosim demo``: the strip-draw test as a co-simulation of press, strip and drawing machine."""
    ap = argparse.ArgumentParser(
        prog="tribocosim demo",
        description="Run models/scenes/demo.toml (press + strip draw + drawing machine, 35 mm pad, 10 MPa, "
                    "140 mm at 0.08 m/s; the FMUs are built into the cache if missing), write the results and "
                    "three figures, and print mu_bar.")
    ap.add_argument("--out", type=Path, default=Path("tribocosim-demo"), help="output folder (default: ./tribocosim-demo)")
    ap.add_argument("--pressure-mpa", type=float, default=None, help="nominal pressure P_N [MPa] (default: the scene's, 10)")
    ap.add_argument("--tool-length", type=float, default=None, help="pad length [m] (default: the scene's, 0.035)")
    ap.add_argument("--no-plot", action="store_true", help="skip the figures")
    args = ap.parse_args(argv)
    from tribocosim.errors import SceneError, TribocosimError

    t0 = time.perf_counter()
    try:
        ensure_fmus()
    except SceneError as exc:
        print(f"tribocosim demo: the FMUs could not be built, so the demo cannot run:\n{exc}", file=sys.stderr)
        return 1
    try:
        result, s, figures = run_demo(args.out, pressure=None if args.pressure_mpa is None else args.pressure_mpa * 1e6,
                                      tool_length=args.tool_length, plot=not args.no_plot)
    except SceneError as exc:
        print(f"tribocosim demo: {exc}", file=sys.stderr)
        return 2
    except TribocosimError as exc:
        print(f"tribocosim demo: the run failed: {exc}", file=sys.stderr)
        return 1
    wall = time.perf_counter() - t0
    strip = result.metadata["fmus"]
    print(f"strip draw co-simulation: press + strip + drawing machine ({len(strip)} FMUs, "
          f"{result.metadata['master']['algorithm']}, step {result.metadata['experiment']['step']:g} s)")
    print(f"P_N = {s['pressure'] / 1e6:.4g} MPa, sliding distance {s['sliding_distance'] * 1e3:.1f} mm, "
          f"beta under the pad at the end {s['beta_mean_end']:.4f}")
    print(f"press holds its set-point within {100 * s['press_error']:.3f} %, the drive its velocity within "
          f"{100 * s['velocity_error']:.3f} % (last 20 % of the draw)")
    print(f"mu_bar = {s['mu_bar']:.4f}   (pull_force / (2 normal_force), last 20 % of the draw; "
          f"strip's mu_mean there: {s['mu_mean_strip']:.4f})")
    print(f"results:  {result.csv_path}  (+ {result.metadata_path.name}, beta field {Path(s['field_file']).name})")
    for f in figures:
        print(f"figure:   {f}")
    print(f"wall time {wall:.1f} s")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
