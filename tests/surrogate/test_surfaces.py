"""Self-affine surfaces: RMS normalisation, PSD exponent -2(1+H) (the PSD by SurfaceTopography), slope definitions,
loading."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from SurfaceTopography import Topography

from tribocosim.errors import ParameterError
from tribocosim.surrogate.coupling import _generate_surfaces
from tribocosim.surrogate.slide_config import SlideConfig
from tribocosim.surrogate.surfaces import (MIN_PIXELS_PER_WAVELENGTH, load_height_map,
                                           predicted_rms_slopes, rms_height, rms_slope,
                                           rolloff_wavelength, self_affine_surface, summit_count,
                                           surface_statistics, surface_wavenumbers)
from tribocosim.surrogate.sweep import load_preset

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
    q, c = Topography(h, (L, L), unit="m", periodic=True).power_spectrum_from_area(collocation="linear",
                                                                                   nb_points=n // 2)
    q, c = q[np.isfinite(c)], c[np.isfinite(c)]
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


# ------------------------------------------------------------------------------------------
# statistics and the roll-off wavelength
# ------------------------------------------------------------------------------------------
def test_summit_count_of_a_checkerboard_of_bumps():
    """cos(2 pi k i/n) cos(2 pi k j/n) has its strict 8-neighbour maxima where both factors are +1 or
    both -1: 2 k^2 of them."""
    n, k = 32, 4
    c = np.cos(2 * np.pi * k * np.arange(n) / n)
    h = 1e-6 * c[:, None] * c[None, :]
    assert summit_count(h) == 2 * k * k
    st = surface_statistics(h, L)
    assert st.summit_count == 2 * k * k and st.summit_density == pytest.approx(2 * k * k / L**2, rel=1e-15)
    assert st.rms_height == rms_height(h) and st.rms_slope_psd == rms_slope(h, L, "spectral")
    assert st.rms_slope_fd == rms_slope(h, L, "finite_difference")
    assert summit_count(np.zeros((8, 8))) == 0, "a flat map has no strict maxima"


def test_predicted_slopes_are_those_of_every_generated_surface():
    """Deterministic amplitudes: the slopes are the moments of the PSD, the same for every seed."""
    n, q_roll, q_cut = 128, 5 * Q0, 30 * Q0
    expect = predicted_rms_slopes(n, L, 0.8, q_roll, q_cut, 1.4e-6)
    for seed in range(3):
        h = self_affine_surface(n, L, 0.8, q_roll, q_cut, rms_height=1.4e-6, seed=seed)
        st = surface_statistics(h, L)
        assert_allclose(st.rms_slope_psd, expect["spectral"], rtol=1e-12, err_msg=f"seed {seed}")
        assert_allclose(st.rms_slope_fd, expect["finite_difference"], rtol=1e-12, err_msg=f"seed {seed}")


def sheet_surfaces(n, ratio, wavelength, seeds):
    q_roll, q_cut = surface_wavenumbers(L, ratio, wavelength)
    return [self_affine_surface(n, L, 0.8, q_roll, q_cut, rms_height=1.4e-6, seed=s) for s in seeds]


def test_rolloff_wavelength_gives_the_papers_sheet_statistics():
    """Paper Sec. 2.4: h_rms 1.40 um, RMS slope 0.34, H = 0.8, L = 500 um; shortest wavelength 1 % of L
    (5.1 pixels of the 512-point grid). A pure power law reaches only ~0.06; the roll-off wavelength
    solved from the PSD moments gives generated surfaces with both targets. Tolerances: the spread over
    seeds (zero up to rounding: deterministic amplitudes) plus the root finder's; the finite-difference
    slope is the PSD moment with the forward-difference weight, below the spectral one by at most
    1 - sinc(pi/4) (one mode at 4 pixels per wavelength)."""
    n, ratio = 512, 0.01
    q_roll, q_cut = surface_wavenumbers(L, ratio)
    assert predicted_rms_slopes(n, L, 0.8, q_roll, q_cut, 1.4e-6)["spectral"] < 0.07
    wavelength = rolloff_wavelength(1.4e-6, 0.34, 0.8, L, n, ratio)
    assert ratio * L < wavelength < L
    stats = np.array([[st.rms_height, st.rms_slope_psd, st.rms_slope_fd, st.summit_density]
                      for st in (surface_statistics(h, L)
                                 for h in sheet_surfaces(n, ratio, wavelength, range(4)))])
    spread = stats.std(axis=0) / stats.mean(axis=0)
    assert np.all(spread[:3] < 1e-13), f"h_rms and slopes must not depend on the seed: {spread}"
    assert spread[3] > 0, "the summit density does"
    assert_allclose(stats[:, 0], 1.4e-6, rtol=1e-12, err_msg="RMS height")
    assert_allclose(stats[:, 1], 0.34, rtol=1e-9, err_msg="RMS slope (PSD)")
    fd = predicted_rms_slopes(n, L, 0.8, *surface_wavenumbers(L, ratio, wavelength), 1.4e-6)
    assert_allclose(stats[:, 2], fd["finite_difference"], rtol=1e-12, err_msg="RMS slope (FD)")
    x = math.pi / MIN_PIXELS_PER_WAVELENGTH
    assert 0.34 * math.sin(x) / x < stats[0, 2] < 0.34
    # solving for the finite-difference slope instead gives that one exactly
    w_fd = rolloff_wavelength(1.4e-6, 0.34, 0.8, L, n, ratio, slope_definition="finite_difference")
    h = sheet_surfaces(n, ratio, w_fd, [0])[0]
    assert_allclose(rms_slope(h, L, "finite_difference"), 0.34, rtol=1e-9)


@pytest.mark.parametrize("args, match", [
    (dict(rms_height=0.6e-6, n=256, wavelength_ratio=0.02),
     r"rms_slope = 0\.34 \(spectral\) with rms_height = 6e-07 m is out of reach .* allowed: \(0\.02\d*, "
     r"0\.26\d*\)"),
    (dict(wavelength_ratio=0.005), r"wavelength_ratio = 0\.005 puts the shortest wavelength on 2\.56 "
                                   r"pixels .* allowed: >= 4 pixels"),
    (dict(rms_slope=float("nan")), r"rms_slope = nan is not finite"),
    (dict(rms_height=-1e-6), r"rms_height = -1e-06 m is out of range"),
    (dict(slope_definition="mean"), r"slope_definition = 'mean' is not allowed"),
])
def test_rolloff_wavelength_refuses_bad_or_unreachable_targets(args, match):
    kw = dict(rms_height=1.4e-6, rms_slope=0.34, hurst=0.8, size=L, n=512, wavelength_ratio=0.01)
    kw.update(args)
    with pytest.raises(ParameterError, match=match):
        rolloff_wavelength(**kw)


def test_preset_surfaces_meet_the_measured_targets():
    """Each surface pair of the quick (the shipped table's), its 128 um domain variation and the paper presets: h_rms
    exact and the RMS slope 0.34 within what the presets' 6-digit roll-off wavelengths allow (their rounding, 5e-6
    relative, times the slope's sensitivity d ln s / d ln lambda_r measured here)."""
    pairs = [(load_preset(name), pair) for name in ("quick", "domain_128um", "paper")
             for pair in load_preset(name).surfaces]
    for sweep, pair in pairs:
        cfg = SlideConfig(**{**sweep.slide, **pair})
        assert cfg.wavelength_ratio * cfg.n >= MIN_PIXELS_PER_WAVELENGTH
        sheet, tool = _generate_surfaces(cfg)
        for h, target, wavelength in ((sheet, cfg.sheet_rms_height, cfg.sheet_rolloff_wavelength),
                                      (tool, cfg.tool_rms_height, cfg.tool_rolloff_wavelength)):
            st = surface_statistics(h, cfg.size)
            _, q_cut = surface_wavenumbers(cfg.size, cfg.wavelength_ratio)
            s_hi, s_lo = (predicted_rms_slopes(cfg.n, cfg.size, cfg.hurst, 2 * math.pi / (wavelength * f),
                                               q_cut, target)["spectral"] for f in (1 - 1e-3, 1 + 1e-3))
            sensitivity = abs(math.log(s_hi / s_lo)) / 2e-3
            assert_allclose(st.rms_height, target, rtol=1e-12)
            assert_allclose(st.rms_slope_psd, 0.34, rtol=2 * sensitivity * 5e-6, err_msg=str(pair))


def test_slide_config_checks_the_rolloff():
    with pytest.raises(ParameterError, match=r"sheet_rolloff_wavelength = 5e-06 m is out of range; "
                                             r"allowed: \(1e-05, 0\.0005\] m"):
        SlideConfig(sheet_rolloff_wavelength=5e-6)
    with pytest.raises(ParameterError, match=r"wavelength_ratio = 0\.02 puts the shortest wavelength on "
                                             r"2\.56 pixels; with tool_rolloff_wavelength set"):
        SlideConfig(n=128, tool_rolloff_wavelength=50e-6)
    with pytest.raises(ParameterError, match=r"tool_rolloff_wavelength = 'x' m is not a number"):
        SlideConfig(tool_rolloff_wavelength="x")
    # without a roll-off the surfaces are today's, bit for bit (a pure power law from L)
    cfg = SlideConfig(n=64, size=128e-6, wavelength_ratio=0.0625)
    q_long = 2.0 * math.pi / cfg.size
    sheet, tool = _generate_surfaces(cfg)
    assert np.array_equal(sheet, self_affine_surface(64, 128e-6, 0.8, q_long, q_long / 0.0625,
                                                     rms_height=1.4e-6, seed=1))
    assert np.array_equal(tool, self_affine_surface(64, 128e-6, 0.8, q_long, q_long / 0.0625,
                                                    rms_height=0.6e-6, seed=2))
