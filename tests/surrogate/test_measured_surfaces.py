"""Measured surfaces: real X3P files written through SurfaceTopography, read back by ``meso surface --from``,
periodized, refused when corrupt, and run through a sweep, a campaign case and a slide."""

import json
import math
import shutil
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from numpy.testing import assert_allclose
from SurfaceTopography import Topography

from tribocosim.errors import ParameterError
from tribocosim.surrogate import measured_surfaces as ms
from tribocosim.surrogate import meso_cli
from tribocosim.surrogate.bem import ContactSolver, gap_against_flat
from tribocosim.surrogate.campaign import expand_cases, run_case
from tribocosim.surrogate.coupling import _generate_surfaces
from tribocosim.surrogate.slide_config import SlideConfig
from tribocosim.surrogate.surfaces import (rms_height, rms_slope, rolloff_wavelength, self_affine_surface,
                                           surface_wavenumbers)
from tribocosim.surrogate.sweep import load_sweep

N, SIZE = 128, 128e-6  # 1 um pixels
RATIO = 5 / 128  # shortest wavelength 5 um, as the quick preset's first pair


def rolloff_sheet(n=N, size=SIZE, seed=1):
    """A generated roll-off sheet with the quick preset's targets (1.40 um, RMS slope 0.34) on this grid."""
    lam = rolloff_wavelength(1.40e-6, 0.34, 0.8, size, n, RATIO)
    q_roll, q_cut = surface_wavenumbers(size, RATIO, lam)
    return self_affine_surface(n, size, 0.8, q_roll, q_cut, rms_height=1.40e-6, seed=seed)


def area_fraction(h, size, pressure=10e6, p_crit=340e6):
    solver = ContactSolver(h.shape[0], size, 55e9, p_crit=p_crit)
    return solver.solve(gap_against_flat(h), pressure).contact_area_fraction


def cli_surface(capsys, *argv):
    rc = meso_cli.main(["surface", *map(str, argv)])
    out = capsys.readouterr()
    return rc, (json.loads(out.out) if rc == 0 else None), out.err


def test_x3p_round_trip_through_meso_surface_keeps_statistics_and_contact_area(tmp_path, capsys):
    h = rolloff_sheet()
    x3p = tmp_path / "sheet.x3p"
    ms.write_x3p(h, SIZE, x3p)
    out = tmp_path / "sheet.npy"
    rc, info, err = cli_surface(capsys, "--from", x3p, "--n", N, "--size", SIZE, "--periodization", "none",
                                "-o", out)
    assert rc == 0, err
    back = np.load(out)
    assert info["measured"]["detrend"] == "mean" and info["measured"]["scan_pixel"] == pytest.approx(1e-6, rel=1e-12)
    assert info["measured"]["sha256"] == ms.file_sha256(x3p)
    assert_allclose(back, h, rtol=0, atol=1e-12 * 1.40e-6, err_msg="heights changed on the round trip")
    for key, ours in (("rms_height", rms_height(h)), ("rms_slope_spectral", rms_slope(h, SIZE, "spectral")),
                      ("rms_slope_finite_difference", rms_slope(h, SIZE, "finite_difference"))):
        assert_allclose(info[key], ours, rtol=1e-12, err_msg=key)
        assert_allclose(info["library"][key], ours, rtol=1e-12, err_msg=f"library {key}")
    assert_allclose(info["library"]["rms_curvature"], ms.library_statistics(h, SIZE)["rms_curvature"], rtol=1e-12)
    a0, a1 = area_fraction(h, SIZE), area_fraction(back, SIZE)
    assert abs(a1 - a0) <= 1e-9 and 0.02 < a0 < 0.05, (a0, a1)
    # a file in micrometres (X3P stores metres; SurfaceTopography's NetCDF keeps the unit) reads back in metres
    microns = tmp_path / "sheet_um.nc"
    Topography(h * 1e6, (SIZE * 1e6, SIZE * 1e6), unit="um", periodic=True).to_netcdf(str(microns))
    assert_allclose(ms.prepared_heights(microns, N, SIZE, detrend="mean", periodization="none")[0], h,
                    rtol=0, atol=1e-12 * 1.40e-6)


def test_our_statistics_equal_the_librarys(tmp_path):
    """RMS height, both RMS slopes and the PSD map: ours (the core's, without the extra) and SurfaceTopography's."""
    h = rolloff_sheet(seed=7)
    lib = ms.library_statistics(h, SIZE)
    assert_allclose(lib["rms_height"], rms_height(h), rtol=1e-13)
    assert_allclose(lib["rms_slope_finite_difference"], rms_slope(h, SIZE, "finite_difference"), rtol=1e-13)
    assert_allclose(lib["rms_slope_spectral"], rms_slope(h, SIZE, "spectral"), rtol=1e-12)
    # the library's 2D PSD map is C(q) = L^2 |h_q|^2 / n^4 of surfaces.py's docstring, whose sum / L^2 is h_rms^2
    _, _, c_map = Topography(h, (SIZE, SIZE), unit="m", periodic=True).power_spectrum_from_area(return_map=True)
    assert_allclose(c_map, SIZE**2 * np.abs(np.fft.fft2(h)) ** 2 / N**4, rtol=1e-10, atol=1e-12 * c_map.max())
    assert_allclose(np.sum(c_map) / SIZE**2, rms_height(h) ** 2, rtol=1e-12)


def test_periodic_smooth_decomposition_keeps_the_patchs_laplacian():
    """Moisan's defining property: the periodic Laplacian of p is the patch's own (free-edge) Laplacian."""
    u = np.random.default_rng(1).standard_normal((20, 24)).cumsum(0).cumsum(1)  # a rough non-periodic patch
    p, s = ms.periodic_smooth_decomposition(u)

    def lap_periodic(a):
        return sum(np.roll(a, k, ax) for k in (1, -1) for ax in (0, 1)) - 4 * a

    def lap_free(a):  # differences to the neighbours inside the patch only
        out = np.zeros_like(a)
        out[1:] += a[:-1] - a[1:]
        out[:-1] += a[1:] - a[:-1]
        out[:, 1:] += a[:, :-1] - a[:, 1:]
        out[:, :-1] += a[:, 1:] - a[:, :-1]
        return out

    assert_allclose(p + s, u, rtol=0, atol=1e-12 * np.abs(u).max())
    assert_allclose(lap_periodic(p), lap_free(u), rtol=0, atol=1e-12 * np.abs(u).max())
    assert abs(s.mean()) < 1e-12 * np.abs(u).max()


@pytest.mark.parametrize("new_pixel", [0.7e-6, 1.3e-6])
def test_resampling_is_exact_for_the_cosine_basis_and_refuses_a_small_map(new_pixel):
    n_scan, d = 90, 1e-6
    x = np.arange(n_scan) * d
    modes = ((3, 5, 1.0), (11, 2, 0.4), (1, 17, -0.3))  # (k, l, amplitude): cos(pi k (x/d + 1/2) / N), ...

    def f(xx, yy):
        return sum(a * np.cos(math.pi * k * (xx[:, None] / d + 0.5) / n_scan)
                   * np.cos(math.pi * l_ * (yy[None, :] / d + 0.5) / n_scan) for k, l_, a in modes)

    n = 40
    got = ms.resample_centred(f(x, x), d, n, new_pixel)
    x0 = 0.5 * ((n_scan - 1) * d - (n - 1) * new_pixel)
    xn = x0 + new_pixel * np.arange(n)
    assert_allclose(got, f(xn, xn), rtol=0, atol=1e-12)
    assert_allclose(ms.resample_centred(f(x, x), d, n, d), f(x, x)[25:65, 25:65], rtol=0, atol=0)
    with pytest.raises(ParameterError, match="a map at least that large"):
        ms.resample_centred(f(x, x), d, 200, new_pixel)


def test_a_non_periodic_patch_is_made_periodic(tmp_path, capsys):
    """A patch cut from a larger surface: its edges meet with steps; the smooth periodization removes them and
    keeps the patch's asperities; the synthesis keeps its height distribution and, closely, its PSD."""
    big = rolloff_sheet(n=2 * N, size=2 * SIZE, seed=3)
    patch = big[40:40 + N, 70:70 + N]
    x3p = tmp_path / "patch.x3p"
    ms.write_x3p(patch, SIZE, x3p, periodic=False)
    out = tmp_path / "patch.npy"
    rc, info, err = cli_surface(capsys, "--from", x3p, "--n", N, "--size", SIZE, "-o", out)
    assert rc == 0, err
    assert info["measured"]["detrend"] == "plane" and info["measured"]["periodization"] == "smooth"
    h = np.load(out)
    detrended = ms.read_scan(x3p, "plane").heights
    p, _ = ms.periodic_smooth_decomposition(detrended)
    assert_allclose(h, p - p.mean(), rtol=0, atol=1e-15)

    def wrap_step(a):  # RMS height difference across the domain's edges over that inside
        edges = np.concatenate([a[0] - a[-1], a[:, 0] - a[:, -1]])
        inside = np.concatenate([(a[1:] - a[:-1]).ravel(), (a[:, 1:] - a[:, :-1]).ravel()])
        return np.sqrt(np.mean(edges**2) / np.mean(inside**2))

    assert wrap_step(detrended) > 3.0 and wrap_step(h) < 1.3, (wrap_step(detrended), wrap_step(h))
    # what the periodization changed is harmonic inside the patch: every asperity keeps its curvature there
    change = h - detrended
    lap = (change[2:, 1:-1] + change[:-2, 1:-1] + change[1:-1, 2:] + change[1:-1, :-2] - 4 * change[1:-1, 1:-1])
    lap_patch = (detrended[2:, 1:-1] + detrended[:-2, 1:-1] + detrended[1:-1, 2:] + detrended[1:-1, :-2]
                 - 4 * detrended[1:-1, 1:-1])
    assert np.abs(lap).max() < 1e-10 * np.abs(lap_patch).max()

    rc, info, err = cli_surface(capsys, "--from", x3p, "--n", N, "--size", SIZE, "--periodization", "synthesis",
                                "--seed", "4", "-o", out)
    assert rc == 0, err
    syn = np.load(out)
    assert_allclose(np.sort(syn.ravel()), np.sort((detrended - detrended.mean()).ravel()), rtol=0, atol=1e-20)
    # other asperities: a copy would correlate ~1; independent maps with ~6 roll-off wavelengths a side scatter ~0.2
    assert abs(np.corrcoef(syn.ravel(), detrended.ravel())[0, 1]) < 0.5, "the synthesis copies the patch"
    # the PSD's shape is p's: its slope (second moment) over its height (zeroth) is p's, to the IAAFT's residual
    assert rms_slope(syn, SIZE) / rms_height(syn) == pytest.approx(rms_slope(p, SIZE) / rms_height(p), rel=0.02)


def test_a_patch_resampled_to_a_coarser_grid(tmp_path, capsys):
    h = rolloff_sheet(n=2 * N, size=2 * SIZE)  # 1 um pixels
    x3p = tmp_path / "fine.x3p"
    ms.write_x3p(h, 2 * SIZE, x3p, periodic=False)
    out = tmp_path / "coarse.npy"
    rc, info, err = cli_surface(capsys, "--from", x3p, "--n", 64, "--size", SIZE, "--detrend", "curvature", "-o", out)
    assert rc == 0, err
    coarse = np.load(out)
    assert coarse.shape == (64, 64) and info["measured"]["detrend"] == "curvature"
    # 2 um pixels: the heights are those of the fine map at every other point, less what the grid cannot hold
    # (wavelengths under 4 um) and the smooth periodization's correction
    assert 0.9 < info["rms_height"] / rms_height(h) < 1.1


def test_a_tool_is_turned_over_about_the_sliding_axis(tmp_path, capsys):
    h = rolloff_sheet()
    x3p = tmp_path / "tool.x3p"
    ms.write_x3p(h, SIZE, x3p)
    out = tmp_path / "tool.npy"
    rc, _, err = cli_surface(capsys, "--from", x3p, "--n", N, "--size", SIZE, "--periodization", "none",
                             "--side", "tool", "-o", out)
    assert rc == 0, err
    tool = np.load(out)
    i, j = np.arange(N)[:, None], np.arange(N)[None, :]
    assert_allclose(tool, -h[i, (-j) % N], rtol=0, atol=1e-12 * 1.40e-6)


def test_corrupt_and_incomplete_files_are_refused(tmp_path, capsys):
    h = rolloff_sheet()
    good = tmp_path / "good.x3p"
    ms.write_x3p(h, SIZE, good)
    truncated = tmp_path / "truncated.x3p"
    truncated.write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    unknown = tmp_path / "notes.dat"
    unknown.write_text("not a height map\n")
    out = tmp_path / "out.npy"
    for path, words in ((truncated, "not a height map SurfaceTopography can read (FileFormatMismatch"),
                        (unknown, "no reader of the"), (tmp_path / "absent.x3p", "does not name an existing file")):
        rc, _, err = cli_surface(capsys, "--from", path, "--n", N, "--size", SIZE, "-o", out)
        assert rc == 2 and str(path) in err and words in err, err
        assert not out.exists(), "no output may be left for a refused file"
    masked = np.ma.masked_array(h, np.zeros_like(h, dtype=bool))
    masked[10:12, 5:8] = np.ma.masked
    holes = tmp_path / "holes.x3p"
    Topography(masked, (SIZE, SIZE), unit="m").to_x3p(str(holes))
    rc, _, err = cli_surface(capsys, "--from", holes, "--n", N, "--size", SIZE, "--periodization", "none", "-o", out)
    assert rc == 2 and "6 undefined point(s) of 16384" in err and "fill_missing" in err, err
    rc, info, err = cli_surface(capsys, "--from", holes, "--n", N, "--size", SIZE, "--periodization", "none",
                                "--fill-missing", "-o", out)
    assert rc == 0 and info["measured"]["missing_points_filled"] == 6, err
    filled = np.load(out)
    assert np.all(np.isfinite(filled)) and abs(filled[11, 6]) < np.abs(h).max()
    rc, _, err = cli_surface(capsys, "--from", good, "--n", N, "--size", SIZE * 1.5, "--periodization", "none",
                             "-o", out)
    assert rc == 2 and "one period of the domain" in err


def test_without_the_extra_a_measured_surface_says_how_to_install_it(tmp_path):
    script = textwrap.dedent(f"""
        import sys
        sys.modules["SurfaceTopography"] = None  # as if the measured extra were not installed
        from tribocosim.surrogate import meso_cli, coupling, campaign, slide_config
        from tribocosim.surrogate.slide_config import SlideConfig
        sheet, tool = coupling._generate_surfaces(SlideConfig(n=32, size=64e-6, wavelength_ratio=0.125))
        assert sheet.shape == (32, 32)
        sys.exit(meso_cli.main(["surface", "--from", {str(tmp_path / 'x.x3p')!r}, "--n", "8", "--size", "1e-5",
                                "-o", {str(tmp_path / 'o.npy')!r}]))
        """)
    (tmp_path / "x.x3p").write_bytes(b"PK")
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2, proc.stderr
    assert 'pip install "tribocosim[measured]"' in proc.stderr and "SurfaceTopography" in proc.stderr, proc.stderr


SWEEP = """
name = "my_surfaces"
[grid]
pressure = [20e6]
velocity = [50.0]
seeds = [11, 12]
[[flakes]]
count = 2
diameter = 8e-6
[[surfaces]]
sheet_file = "scans/sheet.x3p"
tool_file = "scans/tool.x3p"
[[surfaces]]
sheet_file = "scans/sheet.x3p"
tool_seed = 2
surface_periodization = "synthesis"
sheet_seed = 5
[slide]
n = 32
size = 64e-6
wavelength_ratio = 0.125
n_slide_steps = 2
"""


def write_scans(folder):
    (folder / "scans").mkdir(parents=True)
    big = rolloff_sheet(n=2 * N, size=2 * SIZE, seed=9)  # non-periodic 80 um scans at 1 um
    ms.write_x3p(big[:80, :80], 80e-6, folder / "scans" / "sheet.x3p", periodic=False)
    ms.write_x3p(0.5 * big[100:180, 100:180], 80e-6, folder / "scans" / "tool.x3p", periodic=False)
    (folder / "sweep.toml").write_text(SWEEP)


def test_measured_scans_build_a_pair_enter_a_sweep_and_run_a_slide(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    write_scans(a)
    sweep = load_sweep(a / "sweep.toml")
    first = sweep.surfaces[0]
    assert first["sheet_file"] == str((a / "scans" / "sheet.x3p").resolve())
    assert first["sheet_file_sha256"] == ms.file_sha256(a / "scans" / "sheet.x3p")
    cases = expand_cases(sweep)
    assert len(cases) == 6  # 2 pairs x (particle-free + 2 placements)
    cfg = cases[0].config
    sheet, tool = _generate_surfaces(cfg)
    assert_allclose(sheet, ms.prepared_heights(a / "scans" / "sheet.x3p", 32, 64e-6)[0], rtol=0, atol=0)
    assert_allclose(tool, ms.prepared_heights(a / "scans" / "tool.x3p", 32, 64e-6, side="tool")[0], rtol=0, atol=0)
    # the case ids hold the files' contents, not where they lie: the same scans elsewhere resume the same cases
    shutil.copytree(a, b)
    assert [c.case_id for c in expand_cases(load_sweep(b / "sweep.toml"))] == [c.case_id for c in cases]
    # a slide of a campaign, as a worker runs it
    outcome = run_case(cases[1].payload())
    assert outcome["status"] == "done", outcome.get("error")
    assert 0 < outcome["summary"]["mean_contact_fraction"] < 1
    # a scan that changes after the sweep recorded it is refused, by the slide and by a new sweep with the old hash
    (a / "scans" / "sheet.x3p").write_bytes((a / "scans" / "tool.x3p").read_bytes())
    failed = run_case(cases[1].payload())
    assert failed["status"] == "failed" and "has changed since the case was defined" in failed["error"]["message"]
    assert [c.case_id for c in expand_cases(load_sweep(a / "sweep.toml"))][0] != cases[0].case_id


def test_sweep_and_config_refuse_bad_measured_entries(tmp_path):
    write_scans(tmp_path)
    text = (tmp_path / "sweep.toml").read_text()
    (tmp_path / "bad.toml").write_text(text.replace("scans/tool.x3p", "scans/absent.x3p"))
    with pytest.raises(ParameterError, match=r"line 12: \[\[surfaces\]\] entry 1 tool_file: = 'scans/absent.x3p'"):
        load_sweep(tmp_path / "bad.toml")
    wrong_hash = 'tool_file = "scans/tool.x3p"\ntool_file_sha256 = "' + "0" * 64 + '"'
    (tmp_path / "bad.toml").write_text(text.replace('tool_file = "scans/tool.x3p"', wrong_hash))
    with pytest.raises(ParameterError, match=r"line 13: \[\[surfaces\]\] entry 1 tool_file_sha256.*has changed"):
        load_sweep(tmp_path / "bad.toml")
    (tmp_path / "bad.toml").write_text(text.replace("[slide]", '[slide]\nsheet_file = "scans/sheet.x3p"'))
    with pytest.raises(ParameterError, match="sheet_file: is swept by"):
        load_sweep(tmp_path / "bad.toml")
    base = dict(n=32, size=64e-6, wavelength_ratio=0.125)
    for kw, words in ((dict(sheet_file="s.x3p", sheet_rolloff_wavelength=20e-6), "allowed: one of them"),
                      (dict(surface_detrend="plane"), "neither sheet_file nor tool_file"),
                      (dict(sheet_file="s.x3p", surface_detrend="tilt"), "surface_detrend = 'tilt' is not allowed"),
                      (dict(sheet_file="s.x3p", surface_periodization="none"), "allowed: 'mean'"),
                      (dict(sheet_file="s.x3p", sheet_file_sha256="abc"), "64 lower-case hex digits")):
        with pytest.raises(ParameterError, match=words):
            SlideConfig(**base, **kw)
    assert "sheet_file" not in SlideConfig(**base).to_dict(), "a generated pair's configuration (and id) is unchanged"


def guide_surfaces_block() -> str:
    """The [[surfaces]] entries of the user guide's measured-pair example, as the guide prints them."""
    from pathlib import Path

    guide = (Path(__file__).resolve().parents[2] / "docs" / "user-guide.md").read_text()
    section = guide.split("**2. A sweep over your surface pairs.**", 1)[1]
    return section.split("```toml\n", 1)[1].split("```", 1)[0]


def without_surfaces(preset_text: str) -> str:
    """A preset's text with its [[surfaces]] entries removed (the guide: replace them by your pairs)."""
    out, skipping = [], False
    for line in preset_text.splitlines():
        header = line.strip().startswith("[")
        if header:
            skipping = line.strip().startswith("[[surfaces]]")
        if not skipping:
            out.append(line)
    return "\n".join(out) + "\n"


def write_guide_scans(folder, points=300):
    """scans/sheet_1.x3p ... tool_2.x3p of the guide: non-periodic patches at 1 um of a larger generated surface,
    large enough for the quick preset's 256 um domain."""
    (folder / "scans").mkdir(parents=True)
    big = self_affine_surface(2 * points, 2 * points * 1e-6, 0.8, 2 * math.pi / 50e-6, 2 * math.pi / 5e-6,
                              rms_height=1.40e-6, seed=9)  # roll-off at 50 um, shortest wavelength 5 um
    for name, (i, j, scale) in {"sheet_1": (0, 0, 1.0), "sheet_2": (points, 0, 1.0), "tool_1": (0, points, 0.5),
                                "tool_2": (points, points, 0.5)}.items():
        ms.write_x3p(scale * big[i:i + points, j:j + points], points * 1e-6, folder / "scans" / f"{name}.x3p",
                     periodic=False)


def test_the_user_guides_measured_pairs_run_as_written(tmp_path):
    """The guide's example: the quick preset next to the scans, its [[surfaces]] replaced by the guide's three pairs.
    The sweep loads (the defaults of generated sides are not checked for the measured pairs), and the first slide
    steps of a case of every pair run as a campaign's worker runs them."""
    from dataclasses import replace

    from tribocosim.surrogate.sweep import PRESET_DIR

    write_guide_scans(tmp_path)
    (tmp_path / "my_sweep.toml").write_text(without_surfaces((PRESET_DIR / "quick.toml").read_text())
                                            + guide_surfaces_block())
    sweep = load_sweep(tmp_path / "my_sweep.toml")
    assert len(sweep.surfaces) == 3 and sweep.surfaces[0]["tool_file"].endswith("tool_1.x3p")
    cases = expand_cases(sweep)
    for pair in range(3):
        case = next(c for c in cases if c.labels["surface"] == pair and c.config.n_flakes == 12)
        config = replace(case.config, n_slide_steps=2)
        outcome = run_case({"case_id": case.case_id, "config": config.to_dict()})
        assert outcome["status"] == "done", outcome.get("error")
        assert 0 < outcome["summary"]["mean_contact_fraction"] < 1


def test_a_measured_pair_on_a_small_grid_leaves_the_generated_defaults_unchecked(tmp_path):
    """The issue's sweep: two measured pairs on a 32^2 grid, where the default wavelength_ratio 0.02 is below 2/n and
    would be refused for a generated side; a generated side without a wavelength_ratio is refused with a message
    that says the value is the default and where to set it."""
    write_guide_scans(tmp_path, points=80)
    measured = guide_surfaces_block().split("[[surfaces]]                    # pair 3")[0]
    head = ('name = "mine"\n[grid]\npressure = [20e6]\nvelocity = [0.08]\nseeds = [11]\n'
            '[[flakes]]\ncount = 2\ndiameter = 8e-6\n[slide]\nn = 32\nsize = 64e-6\nn_slide_steps = 2\n')
    (tmp_path / "sweep.toml").write_text(head + measured)
    sweep = load_sweep(tmp_path / "sweep.toml")
    assert SlideConfig(**{**sweep.slide, **sweep.surfaces[0]}).generated_sides == ()
    outcome = run_case(expand_cases(sweep)[1].payload())
    assert outcome["status"] == "done", outcome.get("error")
    generated = measured + '[[surfaces]]\nsheet_file = "scans/sheet_1.x3p"\ntool_seed = 2\n'
    (tmp_path / "sweep.toml").write_text(head + generated)
    with pytest.raises(ParameterError) as err:
        load_sweep(tmp_path / "sweep.toml")
    message = str(err.value)
    assert "[[surfaces]] entry 3: wavelength_ratio = 0.02 is out of range" in message, message
    assert ("wavelength_ratio is not set: this is its default; set wavelength_ratio in [slide] or in this "
            "[[surfaces]] entry") in message, message
    # a slide configuration file says the same of its defaults
    (tmp_path / "slide.toml").write_text("n = 32\nsize = 64e-6\n")
    with pytest.raises(ParameterError, match=r"this is its default; set wavelength_ratio in .*slide.toml"):
        SlideConfig.from_toml(tmp_path / "slide.toml")
    (tmp_path / "pair.toml").write_text('n = 32\nsize = 64e-6\nsheet_file = "a.x3p"\ntool_file = "b.x3p"\n')
    assert SlideConfig.from_toml(tmp_path / "pair.toml").generated_sides == ()
