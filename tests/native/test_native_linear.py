"""Native balancing and matrix exponential (tc_linear.c) against components/linear.py and SciPy.

Balancing is scalar arithmetic on powers of two and NumPy's pairwise sums, so it agrees bit for bit. The
exponential differs from linear.expm only in how the matrix products round (NumPy calls BLAS, the C code
sums in order), so the two agree to rounding; we compare the BALANCED matrices, diag(1/d) E diag(d), relative
to their largest entry, since balancing is what makes the small entries accurate in the first place.
"""

from __future__ import annotations

import ctypes
import math

import numpy as np
import scipy.linalg

from tribocosim.components.linear import balance, expm
from tribocosim.components.machine import MachineModel, MachineParameters
from tribocosim.components.press import PressModel, PressParameters

TC_OK, TC_DISCARD, TC_ERROR = 0, 1, 2  # tc_common.h
MAX_DIM = 16  # TC_LINEAR_MAX_DIM


def ptr(a: np.ndarray):
    return a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))


def c_balance(core, M):
    M = np.ascontiguousarray(M, dtype=float)
    d = np.zeros(M.shape[0])
    core.lib.tc_balance(M.shape[0], ptr(M), ptr(d))
    return d


def c_expm(core, M):
    """(status, E) of tc_expm."""
    M = np.ascontiguousarray(M, dtype=float)
    E = np.full(M.shape, -7.0)
    status = core.lib.tc_expm(M.shape[0], ptr(M), ptr(E), core.msg())
    return status, E


def augmented(model, dt):
    """The Van Loan matrix of a model's propagator times dt (as AffineInputPropagator._matrices builds it)."""
    prop = model._prop
    n, m = prop.B.shape
    big = np.zeros((n + 2 * m, n + 2 * m))
    big[:n, :n] = prop.A
    big[:n, n:n + m] = prop.B
    big[n:n + m, n + m:] = np.eye(m)
    return big * dt


def model_matrices():
    for model in (PressModel(PressParameters()), MachineModel(MachineParameters())):
        for dt in (1e-6, 1e-4, 1e-3, 7e-3, 0.1, 3.0):
            yield f"{type(model).__name__} dt={dt}", augmented(model, dt)
    stiff = MachineModel(MachineParameters(drive_stiffness=1e11, speed_ki=1e13, carriage_mass=1.0))
    for dt in (1e-6, 1e-4):  # (unstable closed loop: over longer steps the exponential overflows)
        yield f"stiff machine dt={dt}", augmented(stiff, dt)


def random_matrices():
    rng = np.random.default_rng(7)
    for n in (1, 2, 3, 5, 8, 9, 12, MAX_DIM):
        scales = 10.0 ** rng.uniform(-6, 6, n)
        M = rng.normal(size=(n, n)) * scales[:, None] / scales[None, :]  # badly scaled, balanceable
        M[rng.uniform(size=(n, n)) < 0.3] = 0.0
        yield f"random n={n}", M * (2.0 / max(np.linalg.norm(M, 1), 1e-300))


def balanced_error(E, ref, d):
    Eb = E / d[:, None] * d[None, :]
    Rb = ref / d[:, None] * d[None, :]
    return np.abs(Eb - Rb).max() / np.abs(Rb).max()


def test_balance_is_bit_identical_to_python(native_core):
    for label, M in (*model_matrices(), *random_matrices()):
        np.testing.assert_array_equal(c_balance(native_core, M), balance(M), err_msg=label)


def test_expm_agrees_with_python_to_rounding_and_with_scipy(native_core):
    for label, M in (*model_matrices(), *random_matrices()):
        status, E = c_expm(native_core, M)
        assert status == TC_OK, label
        d = balance(M)
        assert balanced_error(E, expm(M), d) < 1e-12, f"{label}: against linear.expm"
        assert balanced_error(E, scipy.linalg.expm(M), d) < 1e-9, f"{label}: against scipy.linalg.expm"


def test_expm_of_closed_form_cases(native_core):
    status, E = c_expm(native_core, np.zeros((4, 4)))
    assert status == TC_OK
    np.testing.assert_array_equal(E, np.eye(4))  # no scaling, every Taylor term is 0
    lam = np.array([-3.0, -0.5, 0.0, 0.7, 2.0])
    np.testing.assert_allclose(c_expm(native_core, np.diag(lam))[1], np.diag(np.exp(lam)), rtol=1e-14, atol=0)
    J = np.diag(np.ones(3), 1) * 0.5  # nilpotent: exp = I + J + J^2/2 + J^3/6
    np.testing.assert_allclose(c_expm(native_core, J)[1], np.eye(4) + J + J @ J / 2 + J @ J @ J / 6, rtol=1e-15)
    w = 40.0  # rotation: exp([[0, -w], [w, 0]]) = [[cos w, -sin w], [sin w, cos w]], 8 squarings
    np.testing.assert_allclose(c_expm(native_core, np.array([[0.0, -w], [w, 0.0]]))[1],
                               [[math.cos(w), -math.sin(w)], [math.sin(w), math.cos(w)]], atol=1e-13)


def test_expm_refuses_what_python_cannot_compute(native_core):
    for bad in (np.array([[0.0, math.nan], [0.0, 0.0]]), np.array([[math.inf]]), np.full((3, 3), 1e308)):
        status, E = c_expm(native_core, bad)
        assert status == TC_DISCARD
        assert np.all(E == -7.0), "nothing written"
        assert native_core.last_message().startswith("matrix exponential")
    status, _ = c_expm(native_core, np.zeros((MAX_DIM + 1, MAX_DIM + 1)))
    assert status == TC_ERROR
