"""Friction table format: round trip with hash, refusal of tampered files, exact interpolation."""

import json

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tribocosim.errors import ParameterError, TableDomainError, TableError
from tribocosim.components.stripdraw.friction import closed_form_table
from tribocosim.components.stripdraw.parameters import StripDrawParameters
from tribocosim.components.stripdraw import StripDrawModel, make_friction_law
from tribocosim.components.stripdraw.table import FrictionTable, read_table, write_table
from tribocosim.paths import DEFAULT_TABLE


def _trilinear_table():
    P = np.array([1e6, 5e6, 2e7])
    v = np.array([0.0, 0.1, 1.0, 10.0])
    b = np.array([0.0, 0.1, 0.3])
    PP, VV, BB = np.meshgrid(P, v, b, indexing="ij")
    # a trilinear function of (P, v, beta) is reproduced exactly by trilinear interpolation
    mu = 0.2 + 1e-9 * PP - 0.003 * VV - 0.1 * BB + 1e-10 * PP * BB
    return FrictionTable(P, v, b, mu, {"beta_threshold": 0.3, "provenance": "test"})


def test_round_trip_keeps_values_and_checks_hash(tmp_path):
    table = _trilinear_table()
    path = tmp_path / "t.npz"
    digest = write_table(path, table)
    back = read_table(path)
    for name in ("pressure", "velocity", "beta", "mu"):
        assert_allclose(getattr(back, name), getattr(table, name), rtol=0, atol=0, err_msg=name)
    assert back.metadata["content_hash"] == digest
    assert back.content_hash() == digest
    assert back.beta_threshold == 0.3


def test_tampered_table_is_refused(tmp_path):
    path = tmp_path / "t.npz"
    write_table(path, _trilinear_table())
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    arrays["mu"] = arrays["mu"] * 1.01
    np.savez(path, **arrays)
    with pytest.raises(TableError, match="hash"):
        read_table(path)


def test_wrong_format_version_and_missing_file_are_refused(tmp_path):
    path = tmp_path / "t.npz"
    write_table(path, _trilinear_table())
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    meta = json.loads(str(arrays["metadata"]))
    meta["format_version"] = 99
    arrays["metadata"] = np.array(json.dumps(meta))
    np.savez(path, **arrays)
    with pytest.raises(TableError, match="version"):
        read_table(path)
    with pytest.raises(TableError, match="not found"):
        read_table(tmp_path / "missing.npz")


@pytest.mark.parametrize("member, value", [("beta_threshold", "abc"), ("beta_threshold", [1]), ("mu", b"raw bytes")])
def test_a_malformed_member_is_a_table_error_not_a_crash(tmp_path, member, value):
    """Values numpy loads but that are no numbers (found by fuzzing the native reader)."""
    path = tmp_path / "t.npz"
    write_table(path, _trilinear_table())
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    if member == "beta_threshold":
        meta = json.loads(str(arrays["metadata"]))
        meta[member] = value
        arrays["metadata"] = np.array(json.dumps(meta))
    else:
        arrays[member] = np.frombuffer(value, dtype=np.uint8).view("V1")
    np.savez(path, **arrays)
    with pytest.raises(TableError, match="malformed"):
        read_table(path)
    (tmp_path / "garbage.npz").write_bytes(b"\x00\x01 not a zip file")
    with pytest.raises(TableError, match="garbage.npz is not a friction table: not a zip archive"):
        read_table(tmp_path / "garbage.npz")


def test_a_file_that_is_no_table_is_named_for_what_it_is(tmp_path):
    """A text file, an .npy array or an empty file: what it is, not numpy's reading of it (a pickle)."""
    (tmp_path / "table.csv").write_text("pressure,velocity,beta,mu\n1e7,0.08,0,0.15\n")
    np.save(tmp_path / "mu.npy", np.zeros(3))
    (tmp_path / "empty.npz").write_bytes(b"")
    for name, what in (("table.csv", "a text file"), ("mu.npy", "a single numpy array (.npy)"), ("empty.npz", "empty")):
        with pytest.raises(TableError) as err:
            read_table(tmp_path / name)
        message = str(err.value)
        assert f"{tmp_path / name} is not a friction table: {what}; allowed: an .npz archive" in message, message
        assert "pickle" not in message


def test_interpolation_is_exact_on_nodes_and_for_trilinear_functions():
    table = _trilinear_table()
    PP, VV, BB = np.meshgrid(table.pressure, table.velocity, table.beta, indexing="ij")
    mu, clamped = table.interpolate(PP, VV, BB)
    assert_allclose(mu, table.mu, rtol=0, atol=0, err_msg="grid nodes must be reproduced exactly")
    assert not clamped.any()
    rng = np.random.default_rng(3)
    p = rng.uniform(1e6, 2e7, 200)
    v = rng.uniform(0, 10, 200)
    b = rng.uniform(0, 0.3, 200)
    exact = 0.2 + 1e-9 * p - 0.003 * v - 0.1 * b + 1e-10 * p * b
    assert_allclose(table.interpolate(p, v, b)[0], exact, rtol=1e-12, err_msg="trilinear function")
    # negative velocity: the magnitude is used
    assert_allclose(table.interpolate(p, -v, b)[0], exact, rtol=1e-12)


def test_a_table_that_has_made_lookups_pickles_without_its_native_form():
    import pickle

    table = _trilinear_table()
    mu, _ = table.interpolate([2e6], [0.5], [0.2])
    back = pickle.loads(pickle.dumps(table))
    assert "native" not in back.__dict__ and np.array_equal(back.interpolate([2e6], [0.5], [0.2])[0], mu)


def test_out_of_range_policy():
    table = _trilinear_table()
    mu, clamped = table.interpolate([5e5, 5e6, 5e6], [0.1, 20.0, 0.1], [0.1, 0.1, 0.1], policy="clamp")
    assert clamped.tolist() == [True, True, False]
    edge, _ = table.interpolate([1e6, 5e6], [0.1, 10.0], [0.1, 0.1])
    assert_allclose(mu[:2], edge, err_msg="clamped lookups take the edge value")
    with pytest.raises(TableDomainError, match=r"pressure = 5e\+05 Pa is outside .*\[1e\+06, 2e\+07\]"):
        table.interpolate([5e5], [0.1], [0.1], policy="error")


def test_a_query_within_round_off_of_an_axis_end_is_on_the_end_in_python_and_in_the_native_lookup():
    """AXIS_END_TOLERANCE (1e-9 relative): 1e-12 beyond an end is on it, with the end's value; 1e-6 is outside."""
    table = _trilinear_table()
    ends = np.array([1e6 * (1 - 1e-12), 2e7 * (1 + 1e-12)])
    mu, clamped = table.interpolate(ends, [0.1, 0.1], [0.1, 0.1], policy="error")
    assert not clamped.any()
    assert_allclose(mu, table.interpolate([1e6, 2e7], [0.1, 0.1], [0.1, 0.1])[0], rtol=1e-12)
    assert table.interpolate([2e7 * (1 + 1e-6)], [0.1], [0.1])[1].tolist() == [True]
    shipped = read_table(DEFAULT_TABLE)
    last = float(shipped.pressure[-1])
    for factor, inside in ((1 + 1e-12, True), (1 - 1e-12, True), (1 + 1e-6, False)):
        p = StripDrawParameters(table_policy="error")
        m = StripDrawModel(p, make_friction_law(p, shipped))
        inputs = {"normal_force": last * factor * p.tool_length * p.tool_width, "grip_velocity": 0.08}
        if inside:
            assert m.step(1e-3, inputs)["table_clamp_count"] == 0
        else:
            with pytest.raises(TableDomainError, match="pressure = 3.000003e"):
                m.step(1e-3, inputs)


def test_closed_form_table_says_where_it_comes_from():
    table = closed_form_table(StripDrawParameters())
    assert table.provenance == "closed_form"
    assert table.velocity[0] == 0.0 and table.beta[-1] == pytest.approx(table.beta_threshold)
    assert np.all(table.mu >= 0)


def test_make_table_writes_the_closed_form_but_never_over_the_shipped_table(tmp_path, capsys):
    from tribocosim.paths import DEFAULT_TABLE
    from tribocosim.components.stripdraw import make_table

    shipped = DEFAULT_TABLE.read_bytes()
    assert make_table.main([str(DEFAULT_TABLE)]) == 2
    assert "shipped mesoscale table" in capsys.readouterr().err
    assert DEFAULT_TABLE.read_bytes() == shipped
    assert make_table.main([]) == 2
    out = tmp_path / "closed.npz"
    assert make_table.main([str(out)]) == 0
    written = read_table(out)
    assert written.provenance == "closed_form"
    assert_allclose(written.mu, closed_form_table(StripDrawParameters()).mu, rtol=0, atol=0)


def _v2(table):
    rng = np.random.default_rng(4)
    areas = {name: rng.uniform(0, 1e-2, table.mu.shape) for name in
             ("contact_area", "particle_area", "contact_area_std", "particle_area_std")}
    return FrictionTable(table.pressure, table.velocity, table.beta, table.mu, table.metadata, **areas)


def test_version_2_round_trip_keeps_the_areas_and_their_hash(tmp_path):
    t = _v2(_trilinear_table())
    path = tmp_path / "t2.npz"
    digest = write_table(path, t)
    back = read_table(path)
    assert back.version == 2 and back.metadata["format_version"] == 2 and back.content_hash() == digest
    for name in ("mu", "contact_area", "particle_area", "contact_area_std", "particle_area_std"):
        np.testing.assert_array_equal(getattr(back, name), getattr(t, name), err_msg=name)
    # the areas are under the hash
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    arrays["particle_area"] = arrays["particle_area"] * 1.001
    np.savez(path, **arrays)
    with pytest.raises(TableError, match="hash"):
        read_table(path)


def test_version_1_files_stay_readable_and_writable(tmp_path):
    t = _trilinear_table()
    assert t.version == 1
    path = tmp_path / "t1.npz"
    digest = write_table(path, t)
    with np.load(path) as data:
        assert set(data.files) == {"pressure", "velocity", "beta", "mu", "metadata"}
    back = read_table(path)
    assert back.version == 1 and back.content_hash() == digest and back.contact_area is None
    with pytest.raises(ParameterError, match="needs all of"):
        FrictionTable(t.pressure, t.velocity, t.beta, t.mu, t.metadata, contact_area=t.mu)


def _from_10_mpa(path):
    """The shipped table restricted to its pressure nodes from 10 MPa up (10, 20, 30 MPa), written to path."""
    t = read_table(DEFAULT_TABLE)
    keep = t.pressure >= 1e7
    extras = {k: t.array(k)[keep] for k in ("simulated", "contact_area_se", "particle_area_se",
                                            "particle_area_clusters", "particle_area_clusters_se", "mu_se")}
    areas = {k: getattr(t, k)[keep] for k in ("contact_area", "particle_area", "contact_area_std", "particle_area_std")}
    write_table(path, FrictionTable(t.pressure[keep], t.velocity, t.beta, t.mu[keep],
                                    {"beta_threshold": t.beta_threshold}, extras=extras, **areas))
    return path


def test_a_force_on_an_axis_end_to_round_off_is_on_the_table(tmp_path):
    """12250 N on the 35 x 35 mm pad is 9999999.999999998 Pa: a table whose pressure axis starts at 10 MPa takes it
    in the scene checks (the component's input limits), in the model under table_policy = error and in its lookups
    (not counted as clamped); 1e-6 below the axis is refused, the message printing enough digits to show why."""
    from tribocosim.components import registry

    path = _from_10_mpa(tmp_path / "from10.npz")
    params = StripDrawParameters(table_policy="error")
    force = 12250.0
    assert params.pressure(force) < 1e7
    comp = registry.components()["stripdraw"]
    problems, limits = comp.check(params, comp.files(table_file=str(path)), tmp_path)
    assert problems == []
    assert limits["normal_force"](force, "the set-point, 12250 N", "strip") is None
    below = params.normal_force(1e7 * (1 - 1e-6))
    message = limits["normal_force"](below, "the set-point", "strip")
    assert "a nominal pressure of 9.99999 MPa, outside the friction table's pressure axis [10, 30] MPa" in message
    model = StripDrawModel(params, make_friction_law(params, read_table(path)))
    out = model.step(1e-3, {"normal_force": force, "grip_velocity": 0.08})
    assert out["table_clamp_count"] == 0
    with pytest.raises(TableDomainError, match=r"pressure = 9.99999e\+06 Pa is outside the table's range "
                                               r"\[1e\+07, 3e\+07\] Pa \(by more than 1e-09 of the end\)"):
        model.step(1e-3, {"normal_force": below, "grip_velocity": 0.08})
