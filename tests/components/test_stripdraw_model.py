"""Strip-draw model: physics against closed forms, conservation, convergence order, state, bad input."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tribocosim.errors import ParameterError
from tribocosim.components.stripdraw import StripDrawModel, StripDrawParameters, make_friction_law
from tribocosim.components.stripdraw.table import read_table
from tribocosim.paths import DEFAULT_TABLE

PAD = 0.035
P_N = 10e6
F_N = P_N * PAD * PAD


def _model(**kw):
    p = StripDrawParameters(**kw)
    return StripDrawModel(p, make_friction_law(p))


def _ramp(t, v=0.08, t_ramp=0.01):
    return v * min(1.0, t / t_ramp)


def _drive(model, t_end, dt, fn=F_N, v=0.08, t_ramp=0.01):
    """Step with the grip velocity ramped (a velocity step excites undamped elastic waves)."""
    outs = []
    for k in range(int(round(t_end / dt))):
        outs.append(model.step(dt, {"normal_force": fn, "grip_velocity": _ramp((k + 0.5) * dt, v, t_ramp)}))
    return outs


@pytest.mark.parametrize("integrator", ["implicit", "explicit"])
def test_steady_sliding_pull_force_is_two_mu_normal_force(integrator):
    model = _model(friction_model="constant", mu_const=0.15, integrator=integrator, draw_length=0.01, n_elements=160)
    outs = _drive(model, 0.03, 1e-3)
    pull = np.array([o["pull_force"] for o in outs[-10:]])
    assert_allclose(pull.mean(), 2 * 0.15 * F_N, rtol=5e-3, err_msg=f"{integrator}: pull_force vs 2 mu F_N")
    assert_allclose(outs[-1]["mu_mean"], 0.15, rtol=5e-3)


def test_explicit_velocity_step_travels_at_the_bar_wave_speed():
    model = _model(integrator="explicit", n_elements=400, draw_length=0.1, friction_model="constant")
    m = model.mesh
    c = model.params.wave_speed
    probe = m.n_nodes - 1 - 200  # 200 elements from the grip
    distance = m.X[-1] - m.X[probe]
    dt = 0.25 * distance / c / 40
    arrival = None
    for k in range(1, 200):
        model.step(dt, {"normal_force": 0.0, "grip_velocity": 0.08})
        if model.V[probe] >= 0.04:  # half the velocity step: the front has arrived
            t1, v1 = k * dt, model.V[probe]
            arrival = t1 - dt * (v1 - 0.04) / (v1 - v_prev)
            break
        v_prev = model.V[probe]
    assert arrival is not None
    assert_allclose(arrival, distance / c, rtol=0.02, err_msg="wave front arrival time")


def test_debris_without_transport_grows_with_sliding_under_the_pad_then_saturates():
    """zeta = 0, constant P and mu: beta_max = K P min(s, L_T) / (H h_p) (Eq. 37 integrated)."""
    kw = dict(friction_model="constant", zeta=0.0, draw_length=0.06, n_elements=660, archard_k=1e-4, hardness=0.8e9)
    model = _model(**kw, beta_threshold=1.0)
    le = model.mesh.element_length
    rate = 1e-4 * P_N / (0.8e9 * 0.5e-6)
    checked = 0
    for o in _drive(model, 0.7, 5e-3):
        s = o["sliding_distance"]
        if abs(s - PAD) > 3 * le and s > 5 * le:
            assert_allclose(o["beta_max"], rate * min(s, PAD), rtol=0.01, err_msg=f"s = {s}")
            checked += 1
    assert checked > 100
    cap = 0.05
    capped = _model(**kw, beta_threshold=cap)
    for o in _drive(capped, 0.7, 5e-3):
        s = o["sliding_distance"]
        if rate * s < cap * 0.99 and s > 5 * le:
            assert_allclose(o["beta_max"], rate * s, rtol=0.01)
        elif rate * s > cap * 1.01:
            assert o["beta_max"] == cap, "beta is capped at exactly beta_threshold"


@pytest.mark.parametrize("integrator", ["implicit", "explicit"])
def test_transport_conserves_debris_without_source(integrator):
    p = StripDrawParameters(friction_model="constant", zeta=0.7, archard_k=0.0, integrator=integrator, draw_length=0.01, n_elements=120)
    rng = np.random.default_rng(7)
    model = StripDrawModel(p, make_friction_law(p), beta_field=rng.uniform(0.0, 0.2, p.n_elements + 1))
    total0 = model.beta.sum()
    before = model.beta.copy()
    _drive(model, 0.04 if integrator == "implicit" else 0.02, 1e-3)
    assert not np.array_equal(model.beta, before), "debris must have moved"
    assert_allclose(model.beta.sum(), total0, rtol=1e-12, err_msg="total debris")
    assert model.beta.min() >= 0.0


@pytest.mark.parametrize("integrator", ["implicit", "explicit"])
def test_grip_at_rest_gives_no_slip_and_no_debris(integrator):
    model = _model(integrator=integrator, friction_model="closed_form", draw_length=0.01, n_elements=100)
    for _ in range(5):
        out = model.step(1e-3, {"normal_force": F_N, "grip_velocity": 0.0})
    assert np.all(model.U == 0.0) and np.all(model.Up == 0.0)
    assert out["beta_max"] == 0.0 and out["pull_force"] == 0.0 and out["friction_force"] == 0.0


def test_implicit_integrator_is_second_order_in_time():
    """Generalized-alpha is second order: error(dt) ~ dt^2 on a smooth dynamic problem.

    The grip moves smoothly (velocity sin^2 pulse sampled at mid-step, so its displacement is
    second-order accurate); no contact, so the problem is linear; reference: dt / 64.
    """
    t_end = 4e-4
    period = 2e-4

    def run(dt):
        model = _model(integrator="implicit", n_elements=40, draw_length=0.01, rho_inf=0.5, friction_model="constant")
        for k in range(int(round(t_end / dt))):
            t = (k + 0.5) * dt
            v = 0.08 * math.sin(math.pi * min(t, period) / period) ** 2
            model.step(dt, {"normal_force": 0.0, "grip_velocity": v})
        return model.U.copy()

    dts = np.array([4e-6, 2e-6, 1e-6, 5e-7])
    ref = run(dts[-1] / 16)
    errors = np.array([np.max(np.abs(run(dt) - ref)) for dt in dts])
    order = np.polyfit(np.log(dts), np.log(errors), 1)[0]
    assert abs(order - 2.0) < 0.15, f"observed order {order:.3f}, errors {errors}"


@pytest.mark.parametrize("integrator", ["implicit", "explicit"])
def test_state_restore_replays_bit_identically(integrator):
    model = _model(integrator=integrator, friction_model="closed_form", draw_length=0.01, n_elements=80)
    _drive(model, 0.012, 1e-3)
    state = model.get_state()
    first = _drive(model, 0.005, 1e-3)
    fields_first = model.get_state()
    model.set_state(state)
    second = _drive(model, 0.005, 1e-3)
    assert first == second
    assert np.array_equal(model.get_state(), fields_first)


@pytest.mark.parametrize("integrator", ["implicit", "explicit"])
@pytest.mark.parametrize("velocity", ["grip", "slip_rate"])
def test_a_step_refused_after_some_intervals_leaves_the_state_as_it_was(integrator, velocity):
    """A normal force ramped from 10 to 25 MPa over a step of 20 coupling intervals leaves a table that ends at
    20 MPa (table_policy = error) two thirds into the step: the intervals before that were taken, the refusal puts
    back the state of the step's start (bit for bit), and the next step equals that of the state set by set_state."""
    from tribocosim.errors import TableDomainError
    from tribocosim.components.stripdraw.friction import closed_form_table

    p = StripDrawParameters(friction_model="table", table_policy="error", draw_length=0.01, n_elements=60,
                            internal_step=1e-4, friction_velocity=velocity, integrator=integrator)
    table = closed_form_table(p, pressure=np.linspace(1e6, 20e6, 5), velocity=np.linspace(0.0, 1.0, 5),
                              beta=np.linspace(0.0, 1.0, 5))
    model, twin = (StripDrawModel(p, make_friction_law(p, table)) for _ in range(2))
    for k in range(12):
        inputs = {"normal_force": F_N, "grip_velocity": _ramp((k + 0.5) * 1e-3)}
        before = model.get_state()
        with pytest.raises(TableDomainError, match="pressure"):
            model.step(2e-3, inputs, derivatives={"normal_force": (1.5 * F_N / 2e-3, 0.0)})
        assert np.array_equal(model.get_state(), before), f"step {k}: the refused step changed the state"
        twin.set_state(before)
        assert model.step(1e-3, inputs) == twin.step(1e-3, inputs)
        assert np.array_equal(model.get_state(), twin.get_state())


@pytest.mark.parametrize(
    "inputs, name",
    [
        ({"normal_force": float("nan"), "grip_velocity": 0.08}, "normal_force"),
        ({"normal_force": -1.0, "grip_velocity": 0.08}, "normal_force"),
        ({"normal_force": float("inf"), "grip_velocity": 0.08}, "normal_force"),
        ({"normal_force": 100.0, "grip_velocity": float("nan")}, "grip_velocity"),
        ({"normal_force": 100.0, "grip_velocity": float("-inf")}, "grip_velocity"),
    ],
)
def test_bad_inputs_are_rejected_and_leave_the_state_unchanged(inputs, name):
    model = _model(draw_length=0.01, n_elements=50, friction_model="constant")
    _drive(model, 0.003, 1e-3)
    before = model.get_state()
    with pytest.raises(ParameterError, match=name):
        model.step(1e-3, inputs)
    assert np.array_equal(model.get_state(), before)
    with pytest.raises(ParameterError, match="dt"):
        model.step(-1e-3, {"normal_force": 1.0, "grip_velocity": 0.0})


def test_bad_parameters_name_the_parameter_and_the_range():
    with pytest.raises(ParameterError, match=r"density = -5.0 .* allowed: \[1, 100000\]"):
        StripDrawParameters(density=-5.0)
    with pytest.raises(ParameterError, match="zeta = nan"):
        StripDrawParameters(zeta=float("nan"))
    with pytest.raises(ParameterError, match="friction_model"):
        StripDrawParameters(friction_model="coulomb")


@pytest.mark.parametrize("factor", [1e-6, 1.0, 5e3, 1e4])
@pytest.mark.parametrize("pressure, tool_length, n_elements, dt", [(10e6, 0.035, 150, 5e-4), (30e6, 0.14, 600, 1e-3),
                                                                   (30e6, 0.14, 150, 1e-2)])
def test_the_implicit_solver_converges_over_the_declared_shear_stiffness_range(factor, pressure, tool_length,
                                                                              n_elements, dt):
    """The interface penalty's declared range is the range the implicit solve handles: from the softest to the
    stiffest k_s, with the grip ramped to 0.08 m/s over 20 ms under the loaded pad (the start of every draw, where
    the stick/slip set moves most), on the short and the long pad at up to 30 MPa, every step is taken. (A stiff
    interface makes the potential along a Newton step kink at every node that changes between stick and slip; the
    line search steps across them exactly, where backtracking stalls and the step was refused from k_s ~ 5e3 E/h_B.)"""
    p = StripDrawParameters(shear_stiffness_factor=factor, tool_length=tool_length, n_elements=n_elements,
                            draw_length=0.02)
    model = StripDrawModel(p, make_friction_law(p, read_table(DEFAULT_TABLE)))
    force = pressure * tool_length * p.tool_width
    for k in range(int(round(0.03 / dt))):
        model.step(dt, {"normal_force": force, "grip_velocity": 0.08 * min(1.0, k * dt / 0.02)})
    assert model.outputs()["mu_mean"] > 0


def _warnings_of(run) -> list[str]:
    import warnings

    from tribocosim.errors import RangeWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        run()
    return [str(w.message) for w in caught if issubclass(w.category, RangeWarning)]


@pytest.mark.parametrize("velocity, parameters", [(-0.08, {}), (4.0, {}), (0.08, {"draw_length": 0.002})],
                         ids=["grip-moving-back", "one-step-draws-the-strip-out", "beyond-draw-length"])
def test_steps_outside_the_declared_ranges_warn_as_the_fmu_does(stripdraw_fmu_instance, velocity, parameters):
    """The ranges of the strip's ports (ports.py: grip_velocity >= 0, grip_position <= draw_length): the Python model
    warns (RangeWarning) with the native FMU's message, once when a step takes an input outside its range or an
    output leaves it, and computes on."""
    parameters = {"n_elements": 40, "friction_model": "constant", **parameters}
    fmu = stripdraw_fmu_instance("strip", parameters).initialize()
    model = _model(**parameters)
    outputs = []

    def run_model():
        for _ in range(60):
            outputs.append(model.step(1e-3, {"normal_force": 12250.0, "grip_velocity": velocity}))

    python = _warnings_of(run_model)
    for _ in range(60):
        fmu.step(1e-3, 12250.0, velocity)
    native = [m for status, m in fmu.messages if status == 1]
    assert len(python) == 1 and python == [f"StripDrawModel: {m}" for m in native], (python, native)
    assert all(math.isfinite(o["pull_force"]) for o in outputs)


def test_a_restored_state_warns_only_of_what_it_leaves_after_it():
    model = _model(n_elements=40, friction_model="constant", draw_length=0.002)
    step = {"normal_force": 12250.0, "grip_velocity": 0.08}
    assert len(_warnings_of(lambda: _drive(model, 0.05, 1e-3))) == 1  # 3.6 mm drawn
    state = model.get_state()
    fresh = _model(n_elements=40, friction_model="constant", draw_length=0.002)
    fresh.set_state(state)  # beyond draw_length already: no warning for what it held
    assert _warnings_of(lambda: fresh.step(1e-3, step)) == []
    assert len(_warnings_of(lambda: fresh.step(1e-3, {**step, "grip_velocity": -0.01}))) == 1


@pytest.mark.parametrize("inputs, words", [
    ({"normal_force": 100.0}, "inputs has no 'grip_velocity' [m/s]"),
    ({"grip_velocity": 0.08}, "inputs has no 'normal_force' [N]"),
    ({"normal_force": 100.0, "grip_velocity": 0.08, "grip_speed": 1.0}, "'grip_speed', not an input"),
    ({"normal_force": "100", "grip_velocity": 0.08}, "inputs['normal_force'] = '100' is not a number"),
    ({"normal_force": 100.0, "grip_velocity": None}, "inputs['grip_velocity'] = None is not a number"),
    ({"normal_force": True, "grip_velocity": 0.08}, "inputs['normal_force'] = True is not a number"),
    ([100.0, 0.08], "inputs = [100.0, 0.08] is not a dict"),
])
def test_a_missing_unknown_or_non_number_input_is_refused_with_the_state_unchanged(inputs, words):
    model = _model(draw_length=0.01, n_elements=50, friction_model="constant")
    _drive(model, 0.003, 1e-3)
    before = model.get_state()
    with pytest.raises(ParameterError) as err:
        model.step(1e-3, inputs)
    assert words in str(err.value) and "allowed:" in str(err.value), str(err.value)
    assert np.array_equal(model.get_state(), before)
    with pytest.raises(ParameterError, match="'speed', not an input"):
        model.step(1e-3, {"normal_force": 100.0, "grip_velocity": 0.08}, derivatives={"speed": (0.0, 0.0)})
    assert model.step(1e-3, {"normal_force": np.float64(100.0), "grip_velocity": np.int64(0)})["pull_force"] >= 0


@pytest.mark.parametrize("dt", ["1e-3", None, True, [1e-3]])
def test_a_step_length_that_is_not_a_number_is_refused_with_the_state_unchanged(dt):
    model = _model(draw_length=0.01, n_elements=50, friction_model="constant")
    _drive(model, 0.003, 1e-3)
    before = model.get_state()
    with pytest.raises(ParameterError, match=r"dt = .* is not a number; allowed: a real number of seconds > 0"):
        model.step(dt, {"normal_force": 100.0, "grip_velocity": 0.08})
    assert np.array_equal(model.get_state(), before)
