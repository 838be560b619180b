"""Benchmark: the strip-draw model's own step-doubling difference, with and without its
internal time grid.

The strip alone (default parameters, shipped friction table, F_N = 12250 N, grip speed ramped to 0.08 m/s
over 10 ms) is driven to t0 with 0.1 ms steps; from that state it takes one step H and, restored, two steps
H/2, and the table prints e/H = |y(H) - y(2 x H/2)| / H of pull_force and friction_force [N/s], the
quantity co-simulation step doubling divides by its tolerance (error per unit step), for each
internal_step. Inputs are either held over the step ("held": the model's own discretization alone) or the
mean grip speed of each step, as a master with a zero-order hold would pass them ("mean"; the ramp then
adds the input's own first-order difference at t0 = 5 ms).

With internal_step = 0 e/H of friction_force does not fall with H (first order: mu and the contact overlaps
are held over each coupling interval), and that of pull_force stays in the thousands of N/s for H between
1e-5 and 1e-4 s (elastic waves damped differently by the generalized-alpha dissipation); with
internal_step = tau > 0 both are 0 whenever H/2 is a multiple of tau and the inputs are held (the two paths
take the same intervals). Below H = 2 tau (H/2 off the grid) there is no such guarantee: e/H is that of a
model without the grid, from a state integrated with intervals of tau (at 5 ms with tau = 5e-5 s, whose
elastic waves are less damped than after 0.1 ms intervals, e/H of pull_force reaches 1e6 N/s); hence
min_step >= 2 tau and step_quantum = tau in the master. With "mean" inputs during the ramp the two paths
see different inputs, and e/H is the input's own (coupling) difference.

Usage: python benchmarks/bench_strip_step_doubling.py [--t0 0.005 0.5] [--taus 0 1e-4] [--inputs held mean]
"""

from __future__ import annotations

import argparse
import time

from tribocosim.paths import DEFAULT_TABLE
from tribocosim.components.stripdraw.friction import make_friction_law
from tribocosim.components.stripdraw.model import StripDrawModel
from tribocosim.components.stripdraw.parameters import StripDrawParameters
from tribocosim.components.stripdraw.table import read_table

F_N = 12250.0
STEPS = (2e-3, 1e-3, 4e-4, 2e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7)
H0 = 1e-4  # steps to reach t0


V0, T_RAMP = 0.08, 0.01


def grip_velocity(t: float) -> float:
    return V0 * min(1.0, t / T_RAMP)


def mean_velocity(t: float, h: float) -> float:
    """Mean of the grip speed over [t, t + h] (linear ramp, then constant)."""
    a, b = t, t + h
    if b <= T_RAMP:
        return V0 * 0.5 * (a + b) / T_RAMP
    if a >= T_RAMP:
        return V0
    return V0 * ((T_RAMP**2 - a * a) / (2 * T_RAMP) + (b - T_RAMP)) / h


def model_at(t0: float, tau: float, table) -> StripDrawModel:
    p = StripDrawParameters(internal_step=tau)
    m = StripDrawModel(p, make_friction_law(p, table))
    for k in range(int(round(t0 / H0))):
        m.step(H0, {"normal_force": F_N, "grip_velocity": mean_velocity(k * H0, H0)})
    return m


def doubling(m: StripDrawModel, t0: float, H: float, inputs: str) -> tuple[float, float]:
    """e/H of pull_force and friction_force from the model's state (restored afterwards)."""
    saved = m.get_state()

    def u(t, h):
        v = grip_velocity(t0 + 0.5 * H) if inputs == "held" else mean_velocity(t, h)
        return {"normal_force": F_N, "grip_velocity": v}

    y1 = m.step(H, u(t0, H))
    m.set_state(saved)
    m.step(0.5 * H, u(t0, 0.5 * H))
    y2 = m.step(0.5 * H, u(t0 + 0.5 * H, 0.5 * H))
    m.set_state(saved)
    return (abs(y2["pull_force"] - y1["pull_force"]) / H, abs(y2["friction_force"] - y1["friction_force"]) / H)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t0", type=float, nargs="+", default=[0.005, 0.5])
    ap.add_argument("--taus", type=float, nargs="+", default=[0.0, 1e-4])
    ap.add_argument("--inputs", nargs="+", default=["held", "mean"], choices=["held", "mean"])
    args = ap.parse_args()
    table = read_table(DEFAULT_TABLE)
    t_start = time.perf_counter()
    for t0 in args.t0:
        models = {tau: model_at(t0, tau, table) for tau in args.taus}
        for inputs in args.inputs:
            print(f"\nt0 = {t0:g} s, inputs {inputs}: e/H [N/s] of pull_force | friction_force")
            print(f"{'H [s]':>8} " + " ".join(f"{'tau=' + format(tau, 'g'):>25}" for tau in args.taus))
            for H in STEPS:
                cells = []
                for tau in args.taus:
                    ep, ef = doubling(models[tau], t0, H, inputs)
                    cells.append(f"{ep:12.4g} | {ef:10.4g}")
                print(f"{H:8.0e} " + " ".join(f"{c:>25}" for c in cells), flush=True)
    print(f"\n(wall time {time.perf_counter() - t_start:.1f} s)")


if __name__ == "__main__":
    main()
