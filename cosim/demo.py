"""``tribocosim demo``: the default strip-draw case, printing the steady-state mean friction mu_bar.

Default case (paper Sec. 2.1, 7): 35 x 35 mm pad, P_N = 10 MPa, 140 mm draw at 0.08 m/s, the
shipped friction table, the implicit bar integrator. The grip velocity is ramped over 10 ms
(a drive cannot jump in velocity). mu_bar is the mean of mu(t) = pull_force / (2 F_N) (Eq. 1)
over the last 20 % of the draw, the steady-state region where the paper reads it (Sec. 7).
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from components.paths import DEFAULT_TABLE


def run_strip_draw(
    pressure: float = 10e6,
    tool_length: float = 0.035,
    velocity: float = 0.08,
    draw_length: float = 0.14,
    step: float = 1e-3,
    ramp_time: float = 0.01,
    table_file=DEFAULT_TABLE,
    **parameters,
):
    """Run one strip draw with the pure model; return (time, outputs per step, model).

    Parameters
    ----------
    pressure : float
        Nominal contact pressure P_N [Pa]; the normal force is P_N L_T w_T.
    tool_length : float
        Pad length L_T [m].
    velocity : float
        Drawing velocity V0 [m/s].
    draw_length : float
        Draw length [m].
    step : float
        Output step [s].
    ramp_time : float
        Time over which the grip velocity ramps up [s].
    table_file : path
        Friction table (used when ``friction_model`` is ``table``, the default).
    **parameters
        Further :class:`StripDrawParameters` fields.
    """
    from components.stripdraw import StripDrawModel, StripDrawParameters, make_friction_law, read_table

    p = StripDrawParameters(tool_length=tool_length, draw_length=draw_length, **parameters)
    table = read_table(table_file) if p.friction_model == "table" else None
    model = StripDrawModel(p, make_friction_law(p, table))
    normal_force = pressure * p.tool_length * p.tool_width
    t_end = draw_length / velocity + 0.5 * ramp_time
    n = int(round(t_end / step))
    times = step * np.arange(1, n + 1)
    outs = []
    for k in range(n):
        v = velocity * min(1.0, (k + 0.5) * step / ramp_time) if ramp_time > 0 else velocity
        outs.append(model.step(step, {"normal_force": normal_force, "grip_velocity": v}))
    return times, outs, model


def steady_mean(outs, key: str = "mu_mean", fraction: float = 0.2) -> float:
    """Mean of an output over the last ``fraction`` of the run (the steady-state region)."""
    values = np.array([o[key] for o in outs])
    return float(values[int((1.0 - fraction) * values.size):].mean())


def main(argv: list[str] | None = None) -> int:
    """Run the default case and print mu_bar."""
    ap = argparse.ArgumentParser(prog="tribocosim demo", description=__doc__.splitlines()[0])
    ap.add_argument("--pressure-mpa", type=float, default=10.0, help="nominal pressure P_N [MPa]")
    ap.add_argument("--tool-length", type=float, default=0.035, help="pad length [m]")
    ap.add_argument("--integrator", choices=("implicit", "explicit"), default="implicit")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    _, outs, model = run_strip_draw(args.pressure_mpa * 1e6, args.tool_length, integrator=args.integrator)
    wall = time.perf_counter() - t0
    mu_bar = steady_mean(outs)
    last = outs[-1]
    print(f"strip draw: pad {args.tool_length * 1e3:.0f} mm, P_N = {args.pressure_mpa:g} MPa, "
          f"{model.params.draw_length * 1e3:.0f} mm at 0.08 m/s, {args.integrator} integrator, "
          f"friction table {model.law.name} ({getattr(getattr(model.law, 'table', None), 'provenance', '-')})")
    print(f"beta under the pad at the end: mean {last['beta_mean']:.4f}, max {last['beta_max']:.4f}")
    print(f"mu_bar = {mu_bar:.4f}   (steady state, last 20 % of the draw; wall time {wall:.2f} s)")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
