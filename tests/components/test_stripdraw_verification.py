"""Verification of the strip-draw core against what it must satisfy, without a second implementation.

- closed forms: the steady pull 2 mu F_N under uniform sliding (Eq. 1), the debris beta = K P s / (H h_p) produced
  over a slide s without transport (Eq. 37), the elastic wave of the bar (Eq. 2): its speed sqrt(E / rho) and the
  impedance A sqrt(E rho) of a grip pulled at a velocity step, with the explicit integrator;
- conservation: the debris balance produced = on the strip + removed by the cap (transport conserves it exactly);
  the energy balance of the bar without contact (grip work = kinetic + strain energy);
- convergence orders fitted by polyfit(log h, log err): mu_bar first order in the element length, the implicit
  integrator second order in the time step on the linear bar; explicit and implicit integrators agree;
- continuity of the outputs in the step: they are functions of the state, so a vanishing step changes them by a
  vanishing amount (linearly in the step);
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tribocosim.paths import DEFAULT_TABLE
from tribocosim.components.stripdraw import StripDrawModel, StripDrawParameters, make_friction_law, read_table

P = 1e7  # Pa
F_N = P * 0.035 * 0.035  # N on the default pad
V0 = 0.08  # m/s


def _model(**kw) -> StripDrawModel:
    p = StripDrawParameters(**kw)
    return StripDrawModel(p, make_friction_law(p, read_table(DEFAULT_TABLE) if p.friction_model == "table" else None))


def _draw(m: StripDrawModel, n: int, dt: float = 1e-3, ramp: int = 10) -> list[dict]:
    return [m.step(dt, {"normal_force": F_N, "grip_velocity": V0 * min(1.0, (k + 0.5) / ramp)}) for k in range(n)]


@pytest.mark.parametrize("dt", [1e-3, 1e-4])
def test_steady_pull_is_twice_mu_times_the_normal_force(dt):
    """Uniform sliding under a constant mu: pull = 2 mu F_N, F_S = mu F_N (Eq. 1, 28), to within two discretisation
    bounds: the nodes' tributary segments keep their length l_e on the stretched bar, so they cover the pad less
    the strain under it, at most mu F_N / (E A) (3.5e-4; measured 1.75e-4, the mean strain); and the coupling
    holds the contact overlaps over an interval, so a node that reached the pad within the last interval does not
    carry yet: at most the pad's slide in one interval over its length, V0 dt / L_T (2.3e-3 at 1 ms)."""
    mu = 0.15
    m = _model(friction_model="constant", mu_const=mu, draw_length=0.04)
    outs = _draw(m, int(round(0.4 / dt)), dt, ramp=int(round(0.01 / dt)))
    p = m.params
    bound = mu * F_N / (p.youngs_modulus * p.bar_area) + V0 * dt / p.tool_length
    for o in outs[-int(round(0.05 / dt)):]:
        assert abs(o["pull_force"] / (2 * mu * F_N) - 1) <= bound, o
        assert abs(o["friction_force"] / (mu * F_N) - 1) <= bound and abs(o["mu_mean"] / mu - 1) <= bound


def test_debris_produced_without_transport_is_archard():
    """zeta = 0 (no transport), constant mu (cap 1): a node under the pad for the whole slide holds
    beta = K P s / (H h_p) (Eq. 37 integrated, contact weight 1), s its displacement."""
    m = _model(friction_model="constant", zeta=0.0, draw_length=0.01, archard_k=1e-4)
    X0 = m.mesh.X.copy()
    _draw(m, 100)
    p = m.params
    inside = (X0 - 0.5 * m.mesh.element_length > m.mesh.window_lo) & (
        X0 + m.U + 0.5 * m.mesh.element_length < m.mesh.window_hi)
    assert inside.sum() >= 10
    expected = p.archard_k * P * m.U[inside] / (p.hardness * p.particle_thickness)
    np.testing.assert_allclose(m.beta[inside], expected, rtol=1e-12)
    assert np.all(m.beta[X0 + m.U < m.mesh.window_lo - m.mesh.element_length] == 0.0), "no debris off the pad"


def test_elastic_wave_speed_and_impedance():
    """A grip pulled at a velocity step v, no contact, explicit central difference: the grip force is the
    impedance A sqrt(E rho) v (the half bar; pull_force is twice it) until the wave returns, and the tail starts
    to move at L / c, c = sqrt(E / rho) (lumped masses: within 5 %, their dispersion sends precursors)."""
    m = _model(friction_model="constant", integrator="explicit")
    p = m.params
    c, L, v = math.sqrt(p.youngs_modulus / p.density), m.mesh.X[-1], 0.01
    t, force, tail = [], [], []
    for _ in range(60):
        out = m.step(1e-6, {"normal_force": 0.0, "grip_velocity": v})
        t.append(m.time)
        force.append(0.5 * out["pull_force"])
        tail.append(m.U[0])
    t, force, tail = map(np.array, (t, force, tail))
    before = (t > 0.2 * L / c) & (t < 0.8 * L / c)
    np.testing.assert_allclose(force[before].mean(), p.bar_area * math.sqrt(p.youngs_modulus * p.density) * v,
                               rtol=1e-3)
    arrival = t[np.argmax(tail > 1e-3 * v * 1e-6)]
    assert arrival == pytest.approx(L / c, rel=0.05)


@pytest.mark.parametrize("integrator", ["explicit", "implicit"])
def test_the_grip_work_is_the_bars_energy(integrator):
    """No contact: the work of the grip force, int F v dt (trapezoid over 1 us steps), equals the kinetic and strain
    energy of the bar, 1/2 sum m_i V_i^2 + 1/2 k_e sum (U_i+1 - U_i)^2 (the grip node's own motion is prescribed),
    within 0.5 % (measured 3.0e-3 explicit: the power sampled at the steps; -1.0e-4 implicit: its numerical
    damping)."""
    m = _model(friction_model="constant", integrator=integrator, n_elements=60)
    dt, a, ramp = 1e-6, 200.0, 1e-4
    velocity = [a * min(k * dt, ramp) for k in range(201)]
    work, force = 0.0, 0.0
    for k in range(200):
        rate = a if k * dt < ramp - 1e-15 else 0.0
        out = m.step(dt, {"normal_force": 0.0, "grip_velocity": velocity[k]}, {"grip_velocity": (rate, 0.0)})
        work += 0.5 * (force * velocity[k] + 0.5 * out["pull_force"] * velocity[k + 1]) * dt
        force = 0.5 * out["pull_force"]
    U, V, mass = m.U, m.V, m.mesh.mass
    energy = 0.5 * np.sum(mass[:-1] * V[:-1] ** 2) + 0.5 * m.mesh.element_stiffness * np.sum(np.diff(U) ** 2)
    assert energy == pytest.approx(work, rel=5e-3)


@pytest.mark.parametrize("cap", [0.0, 0.02])
def test_debris_balance(cap):
    """sum(beta) - sum(beta_0) = produced - removed, to rounding (transport conserves sum(beta) exactly); with a
    low cap (beta_threshold = 0.02) the cap removes debris."""
    m = _model(beta_threshold=cap, draw_length=0.06, beta_initial=0.001)
    start = float(m.beta.sum())
    _draw(m, 700)
    produced, removed = m.beta_produced, m.beta_removed
    assert produced > 1.0 and (removed > 0.1 * produced if cap else removed == 0.0)
    assert float(m.beta.sum()) - start == pytest.approx(produced - removed, rel=1e-12)


def _mu_bar(n_elements: int) -> float:
    m = _model(friction_model="closed_form", n_elements=n_elements, draw_length=0.06)
    pull = [o["pull_force"] for o in _draw(m, 600)]
    return float(np.mean(pull[-120:])) / (2 * F_N)


def test_mu_bar_converges_first_order_in_the_element_length():
    """docs/model.md section 2: mu_bar converges like l_e. Fitted order over 50-400 elements against 1600: 0.95."""
    ref = _mu_bar(1600)
    n = np.array([50, 100, 200, 400])
    err = np.array([abs(_mu_bar(int(k)) - ref) for k in n])
    order = np.polyfit(np.log(1.0 / n), np.log(err), 1)[0]
    assert 0.8 < order < 1.3, (err, order)


def _linear_bar(n_steps: int, integrator: str = "implicit", T: float = 1e-4, ramp: float = 5e-5, a: float = 400.0):
    """No contact (a linear bar of 8 elements), the grip accelerated at a for ``ramp`` then held; the displacements
    at T. The ramp's velocity is given with its derivative, so each interval takes its exact mean."""
    m = _model(friction_model="constant", integrator=integrator, n_elements=8)
    dt = T / n_steps
    for k in range(n_steps):
        t = k * dt
        if t < ramp - 1e-15:
            m.step(dt, {"normal_force": 0.0, "grip_velocity": a * t}, {"grip_velocity": (a, 0.0)})
        else:
            m.step(dt, {"normal_force": 0.0, "grip_velocity": a * ramp})
    return m.U


def test_implicit_integrator_is_second_order_and_agrees_with_the_explicit_one():
    ref = _linear_bar(8192)
    n = np.array([64, 128, 256, 512])
    err = np.array([np.abs(_linear_bar(k) - ref).max() for k in n])
    order = np.polyfit(np.log(1.0 / n), np.log(err), 1)[0]
    assert 1.8 < order < 2.2, (err, order)  # measured 1.94
    explicit = _linear_bar(1000, "explicit")
    assert np.abs(explicit - ref).max() <= 1e-5 * np.abs(ref).max()  # measured 1.1e-6


def test_explicit_and_implicit_give_the_same_friction():
    """The paper's explicit scheme and the generalized-alpha step on the same draw: mu_bar within 0.2 %
    (docs/model.md section 2)."""
    mu = {}
    for integrator in ("explicit", "implicit"):
        m = _model(integrator=integrator, draw_length=0.02, n_elements=60)
        pull = [o["pull_force"] for o in _draw(m, 250)]
        mu[integrator] = float(np.mean(pull[-50:])) / (2 * F_N)
    assert mu["explicit"] == pytest.approx(mu["implicit"], rel=2e-3)


@pytest.mark.parametrize("integrator", ["implicit", "explicit"])
def test_a_vanishing_step_changes_the_outputs_by_a_vanishing_amount(integrator):
    """Every output is a function of the state at the communication point: after a draw, a step h changes each by
    about its rate times h (h = 1e-13 s: at most 1e-8 relative; a node that entered the pad during the last step
    and was not yet in contact, or a node held below the limit its debris moved, made every step jump by ~1e-3
    within its first 0.3 us), and by ten times that for 10 h (no jump). The rates: the one node that sticks loads
    at k_s V (friction, 2e-9 relative per 1e-13 s); the pull force of the implicit step carries the rounding of the
    draw-sized displacements, k_e ulp(U) (1e-11 relative), which does not scale with h."""
    dt = 1e-3 if integrator == "implicit" else 1e-4
    m = _model(integrator=integrator)
    _draw(m, 500 if integrator == "implicit" else 60, dt, ramp=10)
    before, state = m.outputs(), m.get_state()
    change = {}
    for h in (1e-13, 1e-12):
        m.set_state(state)
        after = m.step(h, {"normal_force": F_N, "grip_velocity": V0})
        change[h] = {k: abs(after[k] - before[k]) / abs(before[k]) for k in before if before[k]}
    assert max(change[1e-13].values()) <= 1e-8, change[1e-13]
    for k in ("friction_force", "mu_mean", "sliding_distance", "grip_position"):
        assert change[1e-12][k] <= 20 * change[1e-13][k] + 1e-14, (k, change)



@pytest.mark.parametrize("rho_inf", [0.5, 0.0])
def test_the_outputs_at_a_communication_point_do_not_depend_on_the_steps_that_reach_it(rho_inf):
    """From one state, the end of 1 ms reached in one step, after a first step of 1e-15 s, 1 ns or 0.3 us, or with a
    last step of 1 ns: friction and debris agree within 1e-6 relative; in two or ten equal steps within 1e-5 (the
    coupling intervals then follow the shorter steps: the first-order error of holding mu over an interval, which
    for two steps is about (1 - 1/2) / (1 - 1/10) = 0.56 of that for ten: 1.0e-6 and 1.8e-6 of beta_mean on the
    shipped table). A 1 ns step moved friction_force by 8.6e-5 and a 0.3 us step by 1.5e-4, more than a whole
    1 ms step: a node that had entered the pad during the step before was not in contact at its end (its friction
    uncounted until the next step's first ~0.2 us, T_max / (k_s V), loaded it), and a node sliding at its
    interval's limit sat below the state's limit (the debris made in the interval had moved it). The bar's pull
    force carries the step sizes' own integration error (1e-4 over the patterns here); a first step short against
    its elastic time scales (0.3 us element transit, 1.5 us interface period) leaves in the algorithmic state a
    high-frequency part that generalized-alpha damps by rho_inf per later step, so with rho_inf = 0 a tiny first
    step changes the end's pull force by 1e-15 and with the default 0.5 by 1.5e-4."""
    m = _model(rho_inf=rho_inf)
    _draw(m, 300, 1e-3, ramp=20)
    state = m.get_state()
    inputs = {"normal_force": F_N, "grip_velocity": V0}
    patterns = {"one": [1e-3], "1e-15 first": [1e-15, 1e-3 - 1e-15], "1 ns first": [1e-9, 1e-3 - 1e-9],
                "0.3 us first": [3e-7, 1e-3 - 3e-7], "1 ns last": [1e-3 - 1e-9, 1e-9], "two": [5e-4, 5e-4],
                "ten": [1e-4] * 10}
    ends = {}
    for name, steps in patterns.items():
        m.set_state(state)
        for h in steps:
            out = m.step(h, inputs)
        ends[name] = out
    for name, out in ends.items():
        tol = 1e-5 if name in ("two", "ten") else 1e-6
        for k in ("friction_force", "mu_mean", "beta_max", "beta_mean", "sliding_distance"):
            assert out[k] == pytest.approx(ends["one"][k], rel=tol), (name, k)
        assert out["pull_force"] == pytest.approx(ends["one"][k := "pull_force"], rel=3e-4), (name, k)
    if rho_inf == 0.0:
        assert ends["1e-15 first"]["pull_force"] == pytest.approx(ends["one"]["pull_force"], rel=1e-12)
        assert ends["1 ns first"]["pull_force"] == pytest.approx(ends["one"]["pull_force"], rel=1e-8)
    for h in (1e-9, 3e-7, 1e-5, 1e-3):  # a single step moves friction_force about linearly in h: no jump
        m.set_state(state)
        m.step(h, inputs)
        change = abs(m.outputs()["friction_force"] / ends["one"]["friction_force"] - 1.0)
        m.set_state(state)
        before = m.outputs()["friction_force"]
        assert abs(m.step(h, inputs)["friction_force"] - before) / before <= 1e-3 * h / 1e-3 + 1e-9, h
