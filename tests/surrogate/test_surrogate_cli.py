"""Tests of ``tribocosim surrogate`` (surrogate.surrogate_cli): build from a sweep file with a
real pool and real slides (tiny), show, compare, and the messages for bad input."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tribocosim.components.stripdraw.table import read_table
from tribocosim.cli import main as tribocosim
from tribocosim.surrogate import surrogate_cli

TINY = (Path(__file__).parent / "data" / "tiny_sweep.toml").read_text().replace('"tiny"', '"tiny-cli"')


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """The tiny campaign and its table, built with one FFTW wisdom file that every slide of this module plans from
    (so that verify's reruns use the plans of the recorded slides: a slide is deterministic for given plans)."""
    d = tmp_path_factory.mktemp("cli")
    (d / "sweep.toml").write_text(TINY)
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("TRIBOCOSIM_FFTW_WISDOM", str(d / "fftw_wisdom.json"))
        rc = tribocosim(["surrogate", "build", "--sweep", str(d / "sweep.toml"), "--out", str(d / "out"),
                         "--workers", "1", "--quiet"])
        yield d, rc


def test_build_writes_cases_fits_and_a_verified_table(built, capsys):
    d, rc = built
    assert rc == 0
    table = read_table(d / "out" / "friction_table.npz")
    assert table.provenance == "mesoscale" and table.mu.shape == (2, 3, 2) and table.version == 4
    assert len(list((d / "out" / "cases").glob("*.json"))) == 2 * 2 * 4
    fits = json.loads((d / "out" / "fits.json").read_text())
    assert fits["content_hash"] == table.metadata["content_hash"]
    assert {"rows", "summary", "unsimulated", "caps", "contact_area"} <= set(fits)
    camp = table.metadata["campaign"]
    assert camp["executor"] == {"executor": "process-pool", "workers": 1} and camp["cases_failed"] == []
    # a rerun computes nothing and rebuilds the same numbers
    rc2 = surrogate_cli.main(["build", "--sweep", str(d / "sweep.toml"), "--out", str(d / "out"),
                              "--table", str(d / "again.npz"), "--quiet"])
    err = capsys.readouterr().err
    assert rc2 == 0 and "16 already finished, 0 computed" in err
    assert "campaign cost: " in err and "core-hours in 16 finished cases" in err
    assert np.array_equal(read_table(d / "again.npz").mu, table.mu)


def test_show_prints_summary_and_plots(built, tmp_path, capsys):
    d, _ = built
    png = tmp_path / "mu.png"
    assert surrogate_cli.main(["show", str(d / "out" / "friction_table.npz"), "--plot", str(png)]) == 0
    out = capsys.readouterr().out
    assert "provenance=mesoscale" in out and "particle_area(beta) per (P, v), goodness of fit" in out
    assert "mu at v = 0.08 m/s" in out and png.stat().st_size > 1000


def test_compare_same_table_is_within_uncertainty(built, capsys):
    d, _ = built
    t = str(d / "out" / "friction_table.npz")
    assert surrogate_cli.main(["compare", t, str(d / "again.npz")]) == 0
    assert json.loads(capsys.readouterr().out)["within_uncertainty"] is True


def test_show_refuses_a_modified_table(built, tmp_path, capsys):
    d, _ = built
    with np.load(d / "out" / "friction_table.npz") as z:
        arrays = {k: z[k] for k in z.files}
    arrays["mu"] = arrays["mu"] * 1.01
    np.savez(tmp_path / "bad.npz", **arrays)
    assert surrogate_cli.main(["show", str(tmp_path / "bad.npz"), "--no-plot"]) == 2
    assert "fails its content hash check" in capsys.readouterr().err


def test_bad_sweep_and_usage_errors(tmp_path, capsys):
    f = tmp_path / "s.toml"
    f.write_text(TINY.replace("seeds = [1, 2, 3]", "seeds = [1, 2, 3]\nbetas = [0.1]"))
    assert surrogate_cli.main(["build", "--sweep", str(f), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert f"sweep file {f}, line 7: [grid] betas: unknown key 'betas'" in err
    assert surrogate_cli.main(["build", "--preset", "nope", "--out", str(tmp_path / "o")]) == 2
    shipped = ['cluster_sizes', 'domain_128um', 'domain_512um', 'first', 'paper', 'quick']
    assert f"preset = 'nope' is not known; available: {shipped}" in capsys.readouterr().err
    assert surrogate_cli.main(["frobnicate"]) == 2
    assert surrogate_cli.main(["build"]) == 2
    assert tribocosim(["surrogate", "--help"]) == 0


def test_build_where_every_case_fails_reports_it(tmp_path, capsys):
    f = tmp_path / "s.toml"
    f.write_text(TINY.replace("pressure = [5e6, 20e6]", "pressure = [5e6]").replace(
        "velocity = [5.0, 50.0]", "velocity = [5.0, 50.0]").replace("n_slide_steps = 4",
                                                                      "n_slide_steps = 4\nbem_max_iter = 1"))
    assert surrogate_cli.main(["build", "--sweep", str(f), "--out", str(tmp_path / "o"), "--workers", "2",
                               "--quiet"]) == 1
    err = capsys.readouterr().err
    errors = sorted((tmp_path / "o" / "cases").glob("*.error.json"))
    assert len(errors) == 8 and "8 of 8 cases" in err and "8 failed; the error of each is in its file" in err
    assert all(f"{e}: ConvergenceError" in err for e in errors), "each failed case named by its error file"
    assert not (tmp_path / "o" / "friction_table.npz").exists()
    assert surrogate_cli.main(["table", "--out", str(tmp_path / "o"), "--allow-failed"]) == 1
    assert "no finished case" in capsys.readouterr().err


def _sampled(table_path, budget_s: float) -> set[str]:
    from tribocosim.surrogate.verify import recorded_cases, sample_cases

    return {r.case.case_id for r in sample_cases(recorded_cases(read_table(table_path)), budget_s)}


def _rewritten(table_path, out, edit) -> Path:
    """The table with its metadata changed by ``edit`` (and a correct content hash)."""
    import dataclasses

    from tribocosim.components.stripdraw.table import write_table

    t = read_table(table_path)
    meta = json.loads(json.dumps(t.metadata))
    edit(meta)
    write_table(out, dataclasses.replace(t, metadata=meta))
    return out


def test_verify_reruns_a_sample_of_the_recorded_cases(built, tmp_path, capsys):
    """The tiny table's cheapest case of every level rebuilt from its recorded sweep (same case ids) and rerun by
    the code that computed it: bit-identical to its recorded results. A table whose recorded result was moved by
    one contact pixel (rebuilt with a correct hash) fails, naming the case: the same code is compared exactly."""
    d, _ = built
    table_path = d / "out" / "friction_table.npz"
    out_json = tmp_path / "verify.json"
    assert surrogate_cli.main(["verify", str(table_path), "--budget-s", "100", "--workers", "1",
                               "--json", str(out_json)]) == 0
    printed = capsys.readouterr().out
    results = json.loads(out_json.read_text())
    assert {r["labels"]["n_flakes"] for r in results} == {0, 2} and all(r["verdict"] == "identical" for r in results)
    assert "2 recorded cases rerun" in printed and "0 differ" in printed

    sampled = _sampled(table_path, 100)

    def move(meta):  # the sampled member with flakes moves by one contact pixel (1/16^2 of A0)
        for case in meta["cases"]:
            if case["case_id"] in sampled and case["labels"]["n_flakes"]:
                case["a_p"] += 1.0 / 16**2

    moved = _rewritten(table_path, tmp_path / "moved.npz", move)
    assert surrogate_cli.main(["verify", str(moved), "--budget-s", "100", "--workers", "1",
                               "--json", str(out_json)]) == 1
    assert "1 differ" in capsys.readouterr().out
    results = json.loads(out_json.read_text())
    assert [r["labels"]["n_flakes"] for r in results if r["verdict"] == "differs"] == [2]
    assert {r["mode"] for r in results} == {"exact"} and "the same mesoscale code" in results[0]["reason"]


def test_verify_says_when_another_code_version_computed_the_cases(built, tmp_path, capsys):
    """Cases recorded as computed by another version of the mesoscale code: the reruns are compared within the
    stated tolerance, with the reason; equal values are still identical, and a recorded A_c that is twice the
    rerun's is never within it (the tolerance leaves the recorded value out of the node's spread)."""
    d, _ = built
    table_path = d / "out" / "friction_table.npz"
    out_json = tmp_path / "verify.json"
    sampled = _sampled(table_path, 100)

    def other(meta):
        meta["case_source_digests"] = ["0123456789ab"]

    def doubled(meta):
        other(meta)
        for case in meta["cases"]:
            if case["case_id"] in sampled and case["labels"]["n_flakes"]:
                case["a_c"] *= 2

    assert surrogate_cli.main(["verify", str(_rewritten(table_path, tmp_path / "doubled.npz", doubled)),
                               "--budget-s", "100", "--workers", "1", "--json", str(out_json)]) == 1
    bad = [r for r in json.loads(out_json.read_text()) if r["verdict"] == "differs"]
    assert len(bad) == 1 and bad[0]["abs_diff"]["a_c"] > bad[0]["tolerance"]["a_c"]
    capsys.readouterr()

    assert surrogate_cli.main(["verify", str(_rewritten(table_path, tmp_path / "other.npz", other)),
                               "--budget-s", "100", "--workers", "1", "--json", str(out_json)]) == 0
    printed = capsys.readouterr().out
    assert "computed by mesoscale code 0123456789ab and this rerun by" in printed and "0 differ" in printed
    results = json.loads(out_json.read_text())
    assert {r["mode"] for r in results} == {"tolerance"} and all(r["verdict"] == "identical" for r in results)


def test_direct_slide_check_of_a_table(built):
    """surrogate.table_check on the tiny table: at a node with the table's own placements the direct slides are
    the members behind it, whose ensemble mean the node holds: no difference in A_p or in mu, the check passes; a
    point outside the table's axes is refused."""
    from tribocosim.errors import TableDomainError
    from tribocosim.surrogate.executors import make_executor
    from tribocosim.surrogate.table_check import run_check

    d, _ = built
    t = read_table(d / "out" / "friction_table.npz")
    beta = float(t.beta[1])
    ex = make_executor(1)
    try:
        on_node = run_check(t, ex, points=((5e6, 50.0, beta),), seeds=(1, 2, 3))[0]
        assert on_node.members == 3 and on_node.all_nodes_simulated and on_node.passed
        assert on_node.direct == pytest.approx(on_node.table, rel=1e-12)
        assert on_node.mu_direct == pytest.approx(on_node.mu_table, rel=1e-12)
        with pytest.raises(TableDomainError, match="beta = .* is outside the table"):
            run_check(t, ex, points=((5e6, 50.0, 1.5 * beta),), seeds=(1,))
    finally:
        ex.close()


def test_show_writes_its_plot_beside_the_table_or_into_out(built, tmp_path, capsys, monkeypatch):
    """Not into the current folder: beside the table by default, into --out DIR when given; a table of the package
    gets no plot unless --out or --plot says where."""
    from tribocosim.paths import DEFAULT_TABLE

    d, _ = built
    monkeypatch.chdir(tmp_path)
    table = tmp_path / "tables" / "mine.npz"
    table.parent.mkdir()
    table.write_bytes((d / "out" / "friction_table.npz").read_bytes())
    assert surrogate_cli.main(["show", str(table)]) == 0
    assert f"plot: {table.parent / 'mine_mu_vs_P.png'}" in capsys.readouterr().out
    assert (table.parent / "mine_mu_vs_P.png").stat().st_size > 1000
    assert surrogate_cli.main(["show", str(table), "--out", str(tmp_path / "figures")]) == 0
    assert (tmp_path / "figures" / "mine_mu_vs_P.png").is_file()
    assert surrogate_cli.main(["show", str(DEFAULT_TABLE)]) == 0
    assert "--out DIR or --plot PNG writes it" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["figures", "tables"], "nothing in the current folder"
    assert not (DEFAULT_TABLE.parent / "friction_table_mu_vs_P.png").exists()


def test_show_of_a_text_file_says_it_is_not_a_table(tmp_path, capsys):
    (tmp_path / "notes.txt").write_text("P [MPa], mu\n10, 0.12\n")
    assert surrogate_cli.main(["show", str(tmp_path / "notes.txt")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "notes.txt is not a friction table: a text file" in err, err


@pytest.mark.slow
def test_the_first_preset_builds_a_table(tmp_path, capsys):
    """The user guide's first campaign: its 15 cases finish, the table is built, and its recorded cases rerun the
    same."""
    from tribocosim.surrogate.campaign import load_records

    out = tmp_path / "first"
    assert surrogate_cli.main(["build", "--preset", "first", "--out", str(out), "--workers", "2", "--quiet"]) == 0
    _, done, unfinished = load_records(out)
    assert len(done) == 15 and not unfinished
    capsys.readouterr()
    assert surrogate_cli.main(["verify", str(out / "friction_table.npz"), "--workers", "2"]) == 0
    assert "0 differ" in capsys.readouterr().out
