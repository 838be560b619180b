"""The LS-DYNA include read back by a reader nobody here wrote (ansys-dyna-core's deck reader, offline), and read
by the rule of the LS-DYNA manual (linear between the table's pressures and along each curve, end values held
beyond them): tribocosim's mu within the accuracy the file states, in both unit systems, for a law that depends on
the velocity and for the shipped one, which does not (a curve of two equal points per pressure), at a given beta and
at the debris of a slide (--slide: mu falls with pressure)."""

from __future__ import annotations

import bisect
import re

import numpy as np
import pytest

from tribocosim.components.friction_export.export_run import DebrisState, ExportRequest, run_export
from tribocosim.components.friction_export.export_units import UNIT_SYSTEMS
from tribocosim.components.friction_export.exported_law import load_law
from tribocosim.components.friction_export.lsdyna_deck import DEFAULT_TABLE_ID

deck_module = pytest.importorskip("ansys.dyna.core.lib.deck", reason="ansys-dyna-core (the test extra) reads the deck")


@pytest.fixture(scope="module")
def law():
    return load_law()


def _export(law, folder, units="mm-t-s", beta=0.1, **options):
    state = DebrisState(beta, "", f"beta = {beta}", {"beta": beta, "how": "given"})
    return run_export(law, ExportRequest("lsdyna", folder / "friction.k", (state,), UNIT_SYSTEMS[units], **options))


def _read(path):
    """(table id, pressures, [(curve id, abscissae, ordinates)]) as ansys-dyna-core reads the file."""
    deck = deck_module.Deck()
    deck.loads(path.read_text())
    tables = [k for k in deck.keywords if type(k).__name__ == "DefineTable"]
    assert len(tables) == 1
    table = tables[0]
    curves = [(int(c.lcid), c.curves["a1"].to_numpy(float), c.curves["o1"].to_numpy(float))
              for c in table.linked_curves]
    assert len(curves) == len([k for k in deck.keywords if type(k).__name__ == "DefineCurve"])
    return int(table.tbid), np.array(list(table.points.data), dtype=float), curves


def manual_lookup(pressures, curves, p, v):
    """LS-DYNA's reading of a *DEFINE_TABLE of curves: each curve linear in its abscissa, the curves linear in the
    table's values, end values held beyond both."""

    def along(x, y, t):
        if t <= x[0]:
            return y[0]
        if t >= x[-1]:
            return y[-1]
        k = bisect.bisect_right(list(x), t) - 1
        return y[k] + (y[k + 1] - y[k]) * (t - x[k]) / (x[k + 1] - x[k])

    if p <= pressures[0]:
        return along(curves[0][1], curves[0][2], v)
    if p >= pressures[-1]:
        return along(curves[-1][1], curves[-1][2], v)
    i = bisect.bisect_right(list(pressures), p) - 1
    lo, hi = along(curves[i][1], curves[i][2], v), along(curves[i + 1][1], curves[i + 1][2], v)
    return lo + (hi - lo) * (p - pressures[i]) / (pressures[i + 1] - pressures[i])


def _stated_accuracy(text: str) -> float:
    flat = " ".join(line.lstrip("$ ").strip() for line in text.splitlines() if line.startswith("$"))
    return float(re.search(r"by at most ([0-9.]+) % \(target", flat).group(1)) / 100


def test_the_reader_finds_every_pressure_and_curve_point(law, tmp_path):
    result = run = _export(law, tmp_path)
    tbid, pressures, curves = _read(tmp_path / "friction.k")
    assert tbid == DEFAULT_TABLE_ID
    assert np.all(np.diff(pressures) > 0), "increasing pressures"
    assert pressures[0] == 1.0 and pressures[-1] == 30.0  # MPa: the table's axis
    assert len(curves) == len(pressures) == run.files[0].shape[0], "one curve per pressure"
    assert [c[0] for c in curves] == [DEFAULT_TABLE_ID + 1 + i for i in range(len(curves))]
    for p, (_, v, m) in zip(pressures, curves):
        assert np.all(np.diff(v) > 0) and v[0] == 0.0 and v[-1] == 500.0  # mm/s
        expected, flagged = law.mu(p * 1e6, v * 1e-3, 0.1)
        assert not flagged.any()
        np.testing.assert_allclose(m, expected, rtol=1e-12)  # 13 significant digits written
    assert result.files[0].accuracy <= 0.005


@pytest.mark.parametrize("velocity_dependent", [False, True])
@pytest.mark.parametrize("units, p_scale, v_scale", [("mm-t-s", 1e6, 1e-3), ("SI", 1.0, 1.0)])
@pytest.mark.parametrize("beta", [0.05, 0.2])
def test_the_manuals_reading_is_tribocosims_mu_within_the_stated_accuracy(law, tmp_path, units, p_scale, v_scale,
                                                                          beta, velocity_dependent,
                                                                          velocity_dependent_table):
    if velocity_dependent:
        law = load_law(table_path=velocity_dependent_table)
    _export(law, tmp_path, units, beta)
    text = (tmp_path / "friction.k").read_text()
    stated = _stated_accuracy(text)
    assert stated <= 0.005
    _, pressures, curves = _read(tmp_path / "friction.k")
    assert all(len(c[1]) == (3 if velocity_dependent else 2) for c in curves), "the table's velocities, or two"
    rng = np.random.default_rng(11)
    p = rng.uniform(1e6, 3e7, 1000)
    v = rng.uniform(0.0, 0.5, 1000)
    fe = np.array([manual_lookup(pressures, curves, a / p_scale, b / v_scale) for a, b in zip(p, v)])
    mu, _ = law.mu(p, v, beta)
    deviation = np.abs(fe - mu) / mu
    assert deviation.max() <= stated, (deviation.max(), stated)
    # beyond the range the file holds its end values: mu at the ends of the table
    assert manual_lookup(pressures, curves, 80e6 / p_scale, 2.0 / v_scale) == pytest.approx(
        float(law.mu(3e7, 0.5, beta)[0]), rel=1e-12)


def test_every_number_sits_in_its_fixed_width_field_with_a_blank_before_it(law, tmp_path):
    _export(law, tmp_path)
    lines = (tmp_path / "friction.k").read_text().splitlines()
    data = [line for line in lines if line and line[0] not in "$*"]
    assert data
    for line in data:
        width = 20 if len(line) in (20, 40) else 10
        assert len(line) % width == 0, repr(line)
        for start in range(0, len(line), width):
            field = line[start:start + width]
            assert field[0] == " " and field.strip(), repr(line)
            if width == 20:
                assert re.fullmatch(r" *-?\d\.\d{12}E[+-]\d\d", field), repr(field)  # 13 significant digits


def test_the_commented_contact_card_has_fs_2_and_fd_the_table_id(law, tmp_path):
    """The card, uncommented (with surface ids put in), is read by the reader as the contact keyword."""
    _export(law, tmp_path, table_id=1234)
    lines = (tmp_path / "friction.k").read_text().splitlines()
    start = lines.index("$*CONTACT_FORMING_ONE_WAY_SURFACE_TO_SURFACE")
    card = []
    for line in lines[start:]:
        if line == "$":
            break
        card.append(line if line.startswith("$#") else line[1:].replace("(blank)", "      1").replace("(tools)",
                                                                                                           "      2"))
    deck = deck_module.Deck()
    deck.loads("*KEYWORD\n" + "\n".join(card) + "\n*END\n")
    contact = deck.keywords[0]
    assert type(contact).__name__ == "ContactFormingOneWaySurfaceToSurface"
    assert (contact.surfa, contact.surfb, contact.fs, contact.fd, contact.fsf) == (1, 2, 2.0, 1234.0, 1.0)
    tbid, _, curves = _read(tmp_path / "friction.k")
    assert tbid == 1234 and curves[0][0] == 1235


def test_the_band_files_share_ids_and_nodes_and_bracket_the_nominal_law(law, tmp_path):
    result = _export(law, tmp_path, band=2.0)
    assert [f.path.name for f in result.files] == ["friction.k", "friction.upper.k", "friction.lower.k"]
    nominal, upper, lower = (_read(f.path) for f in result.files)
    assert nominal[0] == upper[0] == lower[0]
    np.testing.assert_array_equal(nominal[1], upper[1])
    np.testing.assert_array_equal(nominal[1], lower[1])
    for n, u, lo in zip(nominal[2], upper[2], lower[2]):
        assert n[0] == u[0] == lo[0]
        np.testing.assert_array_equal(n[1], u[1])
        assert np.all(u[2] > n[2]) and np.all(lo[2] < n[2])
    # the upper file at its nodes: mu + 2 se(mu), the law's band
    p, (_, v, m) = upper[1][2], upper[2][2]
    np.testing.assert_allclose(m, law.band(p * 1e6, v * 1e-3, 0.1, 2.0)[0], rtol=1e-12)


def test_several_debris_states_can_share_one_deck(law, tmp_path):
    """Two --beta states: each file's table and curves take ids of their own (PyDyna reads each file's table with its
    curves), so both files can be included in one deck, and each state's band files share its ids."""
    states = tuple(DebrisState(b, f"beta{b:g}", f"beta = {b}", {"beta": b, "how": "given"}) for b in (0.05, 0.1))
    run_export(law, ExportRequest("lsdyna", tmp_path / "friction.k", states, UNIT_SYSTEMS["mm-t-s"], band=2.0))
    ids = {}
    for b in ("0.05", "0.1"):
        tbid, _, curves = _read(tmp_path / f"friction.beta{b}.k")
        ids[b] = {tbid, *(c[0] for c in curves)}
        assert _read(tmp_path / f"friction.beta{b}.upper.k")[0] == tbid  # the band shares the state's ids
    assert not ids["0.05"] & ids["0.1"] and min(ids["0.05"]) == 9_450_000



def test_a_slide_gives_mu_falling_with_pressure_and_the_reader_reads_it(tmp_path):
    """--slide 20 (mm, a die radius) with the default export's law (the paper calibration): at each pressure the debris
    a sheet point makes sliding 20 mm there, K P S / (H h_p) below the cap, so mu falls with pressure at every node
    of the file; each curve holds two equal points (the law does not depend on the velocity); the manual's reading
    of what the reader finds is tribocosim's mu at the slide's debris within the stated accuracy."""
    from tribocosim.components.friction_export.named_calibration import DEFAULT
    from tribocosim.cosim.apps.debris_state import DebrisChoice, debris_states

    law = load_law(calibration_path=DEFAULT)
    units = UNIT_SYSTEMS["mm-t-s"]
    (state,) = debris_states(DebrisChoice(slide=20), law, units)
    run_export(law, ExportRequest("lsdyna", tmp_path / "friction.k", (state,), units))
    text = (tmp_path / "friction.k").read_text()
    _, pressures, curves = _read(tmp_path / "friction.k")
    prm = law.params
    beta = np.minimum(prm.archard_k * pressures * 1e6 * 0.02 / (prm.hardness * prm.particle_thickness),
                      [law.cap(p * 1e6, 0.08) for p in pressures])
    node_mu = []
    for p, b, (_, v, m) in zip(pressures, beta, curves):
        assert list(v) == [0.0, 500.0] and m[0] == m[1]
        np.testing.assert_allclose(m[0], law.mu(p * 1e6, 0.08, b)[0], rtol=1e-12)
        assert f"$ the debris after the slide: beta = {b:.6g}" in text
        node_mu.append(m[0])
    assert np.all(np.diff(node_mu) < 0), node_mu
    assert node_mu[0] - node_mu[-1] > 0.05, "from 1 to 30 MPa"
    stated = _stated_accuracy(text)
    rng = np.random.default_rng(5)
    p, v = np.exp(rng.uniform(np.log(1e6), np.log(3e7), 500)), rng.uniform(0.0, 0.5, 500)
    fe = np.array([manual_lookup(pressures, curves, a / 1e6, c / 1e-3) for a, c in zip(p, v)])
    mu, _ = law.mu(p, v, law.beta_after_slide(p, v, 0.02))
    assert (np.abs(fe - mu) / mu).max() <= stated
