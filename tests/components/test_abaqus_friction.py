"""The Abaqus *FRICTION block against the keyword reference's layout (mu, slip rate, contact pressure, temperature,
field variable 1; the first dependency varying fastest), read back by an Abaqus deck reader from PyPI (abq2ccx: its
parser and its reading of tabular data, linear in each variable, end values held), and by multilinear interpolation
written here: tribocosim's mu within the stated accuracy, in both unit systems."""

from __future__ import annotations

import bisect
import itertools
import re

import numpy as np
import pytest

from tribocosim.components.friction_export.export_run import AXIS_STATE, DebrisState, ExportRequest, run_export
from tribocosim.components.friction_export.export_units import UNIT_SYSTEMS
from tribocosim.components.friction_export.exported_law import load_law


@pytest.fixture(scope="module")
def law():
    return load_law()


def _export(law, folder, units="mm-t-s", beta=None, **options):
    state = AXIS_STATE if beta is None else DebrisState(beta, "", f"beta = {beta}", {"beta": beta, "how": "given"})
    path = folder / "friction.inp"
    run_export(law, ExportRequest("abaqus", path, (state,), UNIT_SYSTEMS[units], **options))
    return path


def _stated_accuracy(text: str) -> float:
    flat = " ".join(line[2:].strip() for line in text.splitlines() if line.startswith("**"))
    return float(re.search(r"by at most ([0-9.]+) % \(target", flat).group(1)) / 100


def _data_lines(text: str) -> list[list[str]]:
    return [[x.strip() for x in line.split(",")] for line in text.splitlines() if line and not line.startswith("*")]


def test_the_block_has_the_keyword_references_layout(tmp_path, velocity_dependent_table):
    law = load_law(table_path=velocity_dependent_table)
    text = _export(law, tmp_path).read_text()
    keywords = [line for line in text.splitlines() if line.startswith("*") and not line.startswith("**")]
    assert keywords == ["*SURFACE INTERACTION, NAME=TRIBOCOSIM_FRICTION", "*FRICTION, DEPENDENCIES=1"]
    rows = _data_lines(text)
    assert all(len(r) == 5 and r[3] == "" for r in rows), "mu, slip rate, pressure, temperature (blank), beta"
    values = np.array([[float(r[i]) for i in (0, 1, 2, 4)] for r in rows])
    rates, pressures, betas = (np.unique(values[:, i]) for i in (1, 2, 3))
    expected = [(v, p, b) for b, p, v in itertools.product(betas, pressures, rates)]  # slip rate fastest
    assert [tuple(r) for r in values[:, 1:]] == expected
    assert pressures[0] == 1.0 and pressures[-1] == 30.0 and rates[0] == 0.0 and rates[-1] == 500.0
    assert betas[0] == 0.0 and betas[-1] == pytest.approx(law.simulated_beta_top(law.pressure_axis,
                                                                                   law.velocity_axis), rel=1e-12)
    single = _export(law, tmp_path, beta=0.1).read_text()
    assert [line for line in single.splitlines() if line.startswith("*FRICTION")] == ["*FRICTION"]
    assert all(len(r) == 3 for r in _data_lines(single)), "mu, slip rate, pressure without dependencies"


def test_a_law_without_slip_rate_dependence_leaves_the_slip_rate_blank(law, tmp_path):
    """The shipped table's law does not depend on the velocity: one line per pressure (and beta), the slip-rate field
    blank, which Abaqus reads as no slip-rate dependence; the header says why."""
    text = _export(law, tmp_path).read_text()
    rows = _data_lines(text)
    assert all(len(r) == 5 and r[1] == "" and r[3] == "" for r in rows)
    pairs = [(float(r[2]), float(r[4])) for r in rows]
    assert len(set(pairs)) == len(pairs), "one line per pressure and beta"
    single = _data_lines(_export(law, tmp_path, beta=0.1).read_text())
    assert all(len(r) == 3 and r[1] == "" for r in single)
    assert len({r[2] for r in single}) == len(single)
    flat = " ".join(line[2:].strip() for line in text.splitlines() if line.startswith("**"))
    assert "mu does not depend on the relative sliding velocity over 0-500 mm/s" in flat


def _abq2ccx_mu(module, rows, point):
    """abq2ccx's reading of a tabular card at one point: its _field_slice (linear between the blocks of the last
    variable around the value, an end block held beyond them) applied from the last variable to the first."""
    table = [((r[0],), tuple((float(x) if x else 0.0, x) for x in r[1:])) for r in rows]
    for value in reversed(point):
        table = module._field_slice(table, value)
        assert table is not None
    (values, rest), = table
    assert rest == ()
    return float(values[0])


@pytest.mark.parametrize("units, p_scale, v_scale", [("mm-t-s", 1e6, 1e-3), ("SI", 1.0, 1.0)])
def test_an_abaqus_deck_reader_from_pypi_reads_tribocosims_mu(law, tmp_path, units, p_scale, v_scale):
    abq2ccx = pytest.importorskip("abq2ccx", reason="abq2ccx (the test extra) reads Abaqus decks")
    path = _export(law, tmp_path, units)
    stated = _stated_accuracy(path.read_text())
    assert stated <= 0.005
    blocks = abq2ccx.read_blocks(str(path), abq2ccx.Report())
    friction, = (b for b in blocks if b.keyword == "FRICTION")
    assert friction.param("DEPENDENCIES") == "1"
    rows = abq2ccx.material_rows(friction, 3)  # mu, slip rate, pressure; then temperature and field variable 1
    assert rows is not None and len(rows) == len(_data_lines(path.read_text()))
    rng = np.random.default_rng(7)
    top = law.simulated_beta_top(law.pressure_axis, law.velocity_axis)
    for p, v, b in zip(rng.uniform(1e6, 3e7, 150), rng.uniform(0, 0.5, 150), rng.uniform(0, top, 150)):
        fe = _abq2ccx_mu(abq2ccx, rows, (v / v_scale, p / p_scale, 0.0, b))
        mu = float(law.mu(p, v, b)[0])
        assert abs(fe - mu) / mu <= stated, (p, v, b, fe, mu)
    # its converter keeps one coefficient of a table for CalculiX: the first line's mu, at beta's lowest level
    single = _export(law, tmp_path, units, beta=0.2)
    converted = abq2ccx.convert_text(single.read_text(), base_dir=str(tmp_path)).text.splitlines()
    mu_kept = float(converted[converted.index("*FRICTION") + 1].rstrip(","))
    assert mu_kept == pytest.approx(float(law.mu(1e6, 0.0, 0.2)[0]), rel=1e-11)


def _multilinear_from_rows(rows, point):
    """Linear interpolation in each of slip rate, pressure and beta on the grid the rows span, end values held."""
    grid = {(float(r[1] or 0.0), float(r[2]), float(r[4])): float(r[0]) for r in rows}  # a blank is 0
    axes = [sorted({k[i] for k in grid}) for i in range(3)]
    corners = []
    for axis, x in zip(axes, point):
        if len(axis) == 1:  # one value: the property is constant in it
            corners.append(((axis[0], 1.0),))
            continue
        x = min(max(x, axis[0]), axis[-1])
        i = min(bisect.bisect_right(axis, x) - 1, len(axis) - 2)
        t = (x - axis[i]) / (axis[i + 1] - axis[i])
        corners.append(((axis[i], 1.0 - t), (axis[i + 1], t)))
    return sum(wa * wb * wc * grid[(a, b, c)] for (a, wa), (b, wb), (c, wc) in itertools.product(*corners))


@pytest.mark.parametrize("velocity_dependent", [False, True])
@pytest.mark.parametrize("units, p_scale, v_scale", [("mm-t-s", 1e6, 1e-3), ("SI", 1.0, 1.0)])
def test_multilinear_interpolation_of_the_block_is_tribocosims_mu_within_the_stated_accuracy(
        law, tmp_path, units, p_scale, v_scale, velocity_dependent, velocity_dependent_table):
    if velocity_dependent:
        law = load_law(table_path=velocity_dependent_table)
    text = _export(law, tmp_path, units).read_text()
    stated = _stated_accuracy(text)
    rows = _data_lines(text)
    rng = np.random.default_rng(8)
    top = law.simulated_beta_top(law.pressure_axis, law.velocity_axis)
    p, v, b = rng.uniform(1e6, 3e7, 1000), rng.uniform(0, 0.5, 1000), rng.uniform(0, top, 1000)
    fe = np.array([_multilinear_from_rows(rows, (x / v_scale, y / p_scale, z)) for x, y, z in zip(v, p, b)])
    mu, _ = law.mu(p, v, b)
    assert (np.abs(fe - mu) / mu).max() <= stated


def test_given_beta_levels_are_written_as_they_are_and_the_accuracy_they_leave_is_stated(law, tmp_path):
    text = _export(law, tmp_path, beta_levels=(0.0, 0.05, 0.1, 0.2)).read_text()
    rows = _data_lines(text)
    assert sorted({float(r[4]) for r in rows}) == [0.0, 0.05, 0.1, 0.2]
    stated = _stated_accuracy(text)
    rng = np.random.default_rng(9)
    p, v, b = rng.uniform(1e6, 3e7, 300), rng.uniform(0, 0.5, 300), rng.uniform(0, 0.2, 300)
    fe = np.array([_multilinear_from_rows(rows, (y * 1e3, x / 1e6, z)) for x, y, z in zip(p, v, b)])
    mu, _ = law.mu(p, v, b)
    deviation = (np.abs(fe - mu) / mu).max()
    assert 0.005 < deviation <= stated, "four levels leave mu's curvature in beta: above the target, as stated"
    assert "** WARNING: the FE code's reading of this file deviates" in text


def test_several_debris_states_get_their_own_abaqus_interaction_names(law, tmp_path):
    states = tuple(DebrisState(b, f"beta{b:g}", f"beta = {b}", {"beta": b, "how": "given"}) for b in (0.05, 0.1))
    run_export(law, ExportRequest("abaqus", tmp_path / "friction.inp", states, UNIT_SYSTEMS["mm-t-s"]))
    names = [line for f in sorted(tmp_path.iterdir()) for line in f.read_text().splitlines()
             if line.startswith("*SURFACE INTERACTION")]
    assert names == ["*SURFACE INTERACTION, NAME=TRIBOCOSIM_FRICTION_BETA0_05",
                     "*SURFACE INTERACTION, NAME=TRIBOCOSIM_FRICTION_BETA0_1"]


def test_a_slide_is_read_by_the_deck_reader_with_mu_falling_with_pressure(tmp_path):
    """--slide 20 (mm) with the default export's law (the paper calibration): abq2ccx reads one line per pressure
    (no slip-rate dependence) and its reading at any slip rate is tribocosim's mu at the debris a sheet point makes
    sliding 20 mm at that pressure, within the stated accuracy; mu falls with pressure at every line."""
    abq2ccx = pytest.importorskip("abq2ccx", reason="abq2ccx (the test extra) reads Abaqus decks")
    from tribocosim.components.friction_export.named_calibration import DEFAULT
    from tribocosim.cosim.apps.debris_state import DebrisChoice, debris_states

    law = load_law(calibration_path=DEFAULT)
    units = UNIT_SYSTEMS["mm-t-s"]
    (state,) = debris_states(DebrisChoice(slide=20), law, units)
    path = tmp_path / "friction.inp"
    run_export(law, ExportRequest("abaqus", path, (state,), units))
    text = path.read_text()
    stated = _stated_accuracy(text)
    blocks = abq2ccx.read_blocks(str(path), abq2ccx.Report())
    friction, = (b for b in blocks if b.keyword == "FRICTION")
    rows = abq2ccx.material_rows(friction, 3)
    assert rows is not None and all(r[1] == "" for r in rows)
    line_mu = [float(r[0]) for r in rows]
    assert np.all(np.diff(line_mu) < 0) and np.all(np.diff([float(r[2]) for r in rows]) > 0)
    rng = np.random.default_rng(6)
    for p, v in zip(np.exp(rng.uniform(np.log(1e6), np.log(3e7), 100)), rng.uniform(0, 0.5, 100)):
        fe = _abq2ccx_mu(abq2ccx, rows, (v * 1e3, p / 1e6, 0.0))  # slip rate, pressure, temperature (blank)
        mu = float(law.mu(p, v, law.beta_after_slide(p, v, 0.02))[0])
        assert abs(fe - mu) / mu <= stated, (p, v, fe, mu)
