"""One export: what it refuses (naming the option, writing nothing), the files of several debris states and of the
band, the range, and the table's nodes kept in the grid."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tribocosim.errors import ParameterError
from tribocosim.components.friction_export.export_run import AXIS_STATE, DebrisState, ExportRequest, run_export
from tribocosim.components.friction_export.export_units import UNIT_SYSTEMS
from tribocosim.components.friction_export.exported_law import load_law
from tribocosim.components.stripdraw.friction import closed_form_table
from tribocosim.components.stripdraw.table import write_table

MM = UNIT_SYSTEMS["mm-t-s"]


@pytest.fixture(scope="module")
def law():
    return load_law()


def _state(beta):
    return DebrisState(beta, f"beta{beta:g}", f"beta = {beta:g}", {"beta": beta, "how": "given"})


def _request(tmp_path, fmt="lsdyna", states=None, **options):
    return ExportRequest(fmt, tmp_path / f"friction.{ {'lsdyna': 'k', 'abaqus': 'inp'}.get(fmt, 'json') }",
                         states or (_state(0.1),), MM, **options)


@pytest.mark.parametrize("fmt, states, options, message", [
    ("nastran", None, {}, "FORMAT 'nastran' is not an export format"),
    ("lsdyna", (AXIS_STATE,), {}, "FORMAT lsdyna needs a debris state"),
    ("lsdyna", (_state(1.5),), {}, r"--beta: beta = 1.5 is outside the table's beta axis"),
    ("abaqus", None, {"beta_levels": (0.0, 0.1)}, "--beta-levels gives the levels of a beta axis"),
    ("abaqus", (AXIS_STATE,), {"beta_levels": (0.0, 2.0)}, "--beta-levels: 2 is outside"),
    ("lsdyna", None, {"pressure_range": (5e6, 60e6)}, "--pressure-range 5 60 MPa leaves the table's pressure axis"),
    ("lsdyna", None, {"pressure_range": (20e6, 5e6)}, "--pressure-range 20 5 MPa: two finite pressures"),
    ("lsdyna", None, {"pressure_range": (math.nan, 5e6)}, "--pressure-range nan 5 MPa"),
    ("lsdyna", None, {"band": -1.0}, "--band -1.0"),
    ("lsdyna", None, {"band": math.nan}, "--band nan"),
    ("lsdyna", None, {"tolerance": 0.0}, "--tolerance 0.0"),
    ("lsdyna", None, {"table_id": 0}, "--table-id 0"),
])
def test_a_bad_request_names_the_option_and_writes_nothing(law, tmp_path, fmt, states, options, message):
    with pytest.raises(ParameterError, match=message):
        run_export(law, _request(tmp_path, fmt, states, **options))
    assert not list(tmp_path.iterdir())


def test_a_beta_above_the_cap_is_refused(tmp_path):
    """With s = 4 blocked flakes cover the contact at a share of 1/4: the strip-draw model caps beta there."""
    law = load_law(settings={"particle_area_scale": 4.0})
    cap = min(law.cap(p, v) for p in law.table.pressure for v in law.table.velocity)
    assert cap < 0.3
    with pytest.raises(ParameterError, match="above the cap of beta"):
        run_export(law, _request(tmp_path, states=(_state(min(0.3, cap + 0.02)),)))
    assert not list(tmp_path.iterdir())


def test_a_band_needs_standard_errors(tmp_path):
    path = tmp_path / "closed_form.npz"
    write_table(path, closed_form_table(pressure=np.array([1e6, 3e7]), velocity=np.array([0.0, 0.5]),
                                        beta=np.array([0.0, 0.2])))
    law = load_law(table_path=path)
    out = tmp_path / "out"
    out.mkdir()
    with pytest.raises(ParameterError, match="--band needs a table with the ensemble standard errors"):
        run_export(law, _request(out, states=(_state(0.02),), band=2.0))
    assert not list(out.iterdir())
    run_export(law, _request(out, states=(_state(0.02),)))  # without the band it is written
    assert [p.name for p in out.iterdir()] == ["friction.k"]


def test_several_states_and_a_band_make_one_file_each(law, tmp_path):
    result = run_export(law, _request(tmp_path, states=(_state(0.05), _state(0.1)), band=2.0))
    names = [f.path.name for f in result.files]
    assert names == ["friction.beta0.05.k", "friction.beta0.05.upper.k", "friction.beta0.05.lower.k",
                     "friction.beta0.1.k", "friction.beta0.1.upper.k", "friction.beta0.1.lower.k"]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(names)
    assert all(f.accuracy <= 0.005 for f in result.files)
    summary = "\n".join(result.summary())
    assert "range: contact pressure 1-30 MPa, relative sliding velocity 0-500 mm/s" in summary
    assert "beyond it: LS-DYNA holds the end values (clamps)" in summary


def test_the_grid_holds_the_tables_nodes_in_the_range_and_its_ends(tmp_path, velocity_dependent_table):
    import json

    law = load_law(table_path=velocity_dependent_table)
    result = run_export(law, _request(tmp_path, "table", pressure_range=(3e6, 25e6)))
    doc = json.loads(result.files[0].path.read_text())
    p, v = (np.array(a["values"]) for a in doc["axes"])
    assert p[0] == pytest.approx(3.0) and p[-1] == pytest.approx(25.0)
    for node in (5.0, 10.0, 20.0):
        assert np.isclose(p, node, rtol=1e-12).any()
    np.testing.assert_allclose(v, [0.0, 80.0, 500.0])
    assert "independent" not in doc["axes"][1] and not result.files[0].one_velocity
    assert "range: contact pressure 3-25 MPa" in result.range_line


def test_a_law_that_does_not_depend_on_the_velocity_is_written_at_one(law, tmp_path):
    """The shipped table's law is the same at 0, 0.08 and 0.5 m/s (its slides do not depend on v in the overdamped
    regime): the grid's velocity axis collapses to one value, the FE code's reading of it is the law within the
    accuracy stated at every velocity of the range (the random points of the check), and the command says so."""
    import json

    from tribocosim.components.friction_export.grid_refinement import multilinear

    v_nodes = law.table.velocity
    for beta in (0.0, 0.05, 0.2):  # the law at the table's velocity nodes: equal, to the bit here
        mu, _ = law.mu(law.table.pressure[:, None], v_nodes[None, :], beta)
        assert np.all(mu == mu[:, :1])
    result = run_export(law, _request(tmp_path, "table", states=(_state(0.1),)))
    (f,) = result.files
    doc = json.loads(f.path.read_text())
    p_axis, v_axis = doc["axes"]
    assert f.one_velocity and f.shape[1] == 1 and v_axis["values"] == [0.0]
    assert v_axis["independent"] is True and v_axis["range"] == [0.0, 500.0]
    rng = np.random.default_rng(4)
    p, v = rng.uniform(1e6, 3e7, 2000), rng.uniform(0.0, 0.5, 2000)
    fe = multilinear([np.array(p_axis["values"]) * 1e6, np.array([0.0])], np.array(doc["mu"])[..., None], (p, v))
    exact, _ = law.mu(p, v, 0.1)
    assert (np.abs(fe[:, 0] - exact) / exact).max() <= f.accuracy
    summary = result.summary()
    assert "1 velocity (mu does not depend on it)" in summary[0]
    assert summary[1].startswith("velocity: mu does not depend on the relative sliding velocity over 0-500 mm/s: ")
    assert "at 0, 80, 500 mm/s" in summary[1]
    assert any("velocity: mu does not depend" in line for line in doc["header"])
