"""Self-affine surfaces: RMS normalisation, PSD exponent -2(1+H), slope definitions, loading."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tribocosim.components.errors import ParameterError
from tribocosim.surrogate.surfaces import (load_height_map, radial_psd, rms_height, rms_slope,
                                self_affine_surface)

L = 500e-6
Q0 = 2.0 * math.pi / L


@pytest.mark.parametrize("definition", ["spectral", "finite_difference"])
def test_normalisation_to_rms_slope_and_height(definition):
    h = self_affine_surface(128, L, 0.8, 4 * Q0, 32 * Q0, rms_slope=0.34, seed=3,
                            slope_definition=definition)
    assert_allclose(rms_slope(h, L, definition), 0.34, rtol=1e-12,
                    err_msg=f"RMS slope ({definition}) not normalised")
    h2 = self_affine_surface(128, L, 0.8, 4 * Q0, 32 * Q0, rms_height=1.4e-6, seed=3)
    assert_allclose(rms_height(h2), 1.4e-6, rtol=1e-12, err_msg="RMS height not normalised")
    assert abs(h2.mean()) < 1e-12 * 1.4e-6, "generated surface must have zero mean"


@pytest.mark.parametrize("hurst", [0.5, 0.8])
def test_psd_follows_power_law_with_plateau_and_cutoff(hurst):
    n, kr, ks = 256, 6, 96
    h = self_affine_surface(n, L, hurst, kr * Q0, ks * Q0, rms_height=1e-6, seed=1)
    q, c = radial_psd(h, L)
    band = (q > 2 * kr * Q0) & (q < 0.5 * ks * Q0)
    slope = np.polyfit(np.log(q[band]), np.log(c[band]), 1)[0]
    assert_allclose(slope, -2.0 * (1.0 + hurst), rtol=0.01,
                    err_msg="radial PSD exponent differs from -2(1+H)")
    plateau = c[(q > 1.5 * Q0) & (q < (kr - 1.5) * Q0)]
    assert_allclose(plateau, plateau.mean(), rtol=0.05, err_msg="PSD not flat below q_roll")
    assert c[q > (ks + 1) * Q0].max() < 1e-12 * c.max(), "PSD not zero above q_cut"


def test_slope_to_height_ratio_matches_the_continuum_integral():
    # h'^2 / h^2 = int q^3 C dq / int q C dq for the prescribed C(q) (plateau from 2 pi/L)
    n, kr, ks, H = 256, 8, 64, 0.8
    h = self_affine_surface(n, L, H, kr * Q0, ks * Q0, rms_slope=0.34, seed=1)
    ql, qr, z = Q0, kr * Q0, ks / kr
    i1 = (qr**2 - ql**2) / 2 + qr**2 * (1 - z ** (-2 * H)) / (2 * H)
    i3 = (qr**4 - ql**4) / 4 + qr**4 * (z ** (2 - 2 * H) - 1) / (2 - 2 * H)
    assert_allclose(rms_slope(h, L) / rms_height(h), math.sqrt(i3 / i1), rtol=0.01,
                    err_msg="h'_rms / h_rms differs from the integral of the prescribed PSD")


def test_finite_difference_slope_equals_its_spectral_form():
    n = 64
    h = self_affine_surface(n, L, 0.7, 2 * Q0, 32 * Q0, rms_height=1e-6, seed=5)
    dx = L / n
    k = 2 * np.pi * np.fft.fftfreq(n, d=dx)
    weight = (4 * np.sin(k[:, None] * dx / 2) ** 2 + 4 * np.sin(k[None, :] * dx / 2) ** 2) / dx**2
    parseval = math.sqrt(np.sum(weight * np.abs(np.fft.fft2(h)) ** 2) / n**4)
    assert_allclose(rms_slope(h, L, "finite_difference"), parseval, rtol=1e-12,
                    err_msg="forward-difference slope disagrees with its Fourier form")
    assert rms_slope(h, L, "finite_difference") < rms_slope(h, L, "spectral")


def test_seed_reproducibility():
    a = self_affine_surface(32, L, 0.8, 2 * Q0, 16 * Q0, rms_height=1e-6, seed=7)
    b = self_affine_surface(32, L, 0.8, 2 * Q0, 16 * Q0, rms_height=1e-6, seed=7)
    c = self_affine_surface(32, L, 0.8, 2 * Q0, 16 * Q0, rms_height=1e-6, seed=8)
    assert np.array_equal(a, b) and not np.allclose(a, c)


def test_load_height_map_formats(tmp_path):
    h = self_affine_surface(16, L, 0.8, 2 * Q0, 8 * Q0, rms_height=1e-6, seed=2)
    np.save(tmp_path / "h.npy", h)
    np.savetxt(tmp_path / "h.txt", h)
    np.savetxt(tmp_path / "h.csv", h, delimiter=",")
    for name in ("h.npy", "h.txt", "h.csv"):
        assert_allclose(load_height_map(tmp_path / name), h, rtol=1e-15, atol=0,
                        err_msg=f"{name} did not round-trip")


@pytest.mark.parametrize("content, words", [
    ("1 2 3\n4 5 6\n", ["shape", "(2, 3)"]),
    ("1 2\nnan 4\n", ["non-finite"]),
])
def test_load_height_map_rejects_bad_maps(tmp_path, content, words):
    path = tmp_path / "bad.txt"
    path.write_text(content)
    with pytest.raises(ParameterError) as err:
        load_height_map(path)
    assert all(w in str(err.value) for w in words) and "bad.txt" in str(err.value)
    with pytest.raises(ParameterError, match="does not name an existing file"):
        load_height_map(tmp_path / "missing.npy")


@pytest.mark.parametrize("kwargs, name", [
    (dict(q_cut=200 * Q0), "q_cut"),
    (dict(hurst=0.0), "hurst"),
    (dict(size=-1.0), "size"),
    (dict(rms_height=1e-6, rms_slope=0.3), "rms_height"),
    (dict(rms_slope=None), "rms_height"),
])
def test_bad_parameters_name_the_argument(kwargs, name):
    args = dict(n=64, size=L, hurst=0.8, q_roll=2 * Q0, q_cut=16 * Q0, rms_slope=0.3)
    args.update(kwargs)
    with pytest.raises(ParameterError, match=name):
        self_affine_surface(**args)
