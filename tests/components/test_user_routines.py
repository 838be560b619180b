"""The user friction routines (``tribocosim export vfriction|fric|usrfrc``) with real compilers: each routine and its C
core compile with their documented argument lists, the embedded table is the FMU's bit for bit, and a stand-in for
Abaqus/Explicit's side of VFRICTION (tests/components/fe_harness) replays the contact increments of the StripDraw
model's own strip-draw run: the sheet's nodes passing under the 35 mm pad at the model's pressure with the model's slips.

What the replay compares, and the tolerances it derives:

- beta per node after the pass (zeta = 0 in the model, so that every node keeps the debris it makes): the model adds
  to a node per coupling interval the source fl(fl(fl(K P |dU|) w) / (H h_p)), the routine fl(fl(K P' s) / (H h_p))
  with s = w |dU| (its slip increment, the slide under the pad) and P' = fl(fl(P A) / A) (normal force over contact
  area), each within 4 units in the last place u of the exact source, so the two sources differ by at most 8 u of it,
  and each sum rounds once per interval (at most u beta each). Over the n intervals a node spends under the pad:
  |beta_routine - beta_model| <= (2 n + 8) u beta (u = 2^-53).
- the friction force per increment: the routine's sum of mu F_N over the block against the model's friction limits of
  the interval (friction_limit, mu P of its state at the interval's start) times the same contact areas: every term
  within 4 u (the law's table lookup at the slip rate instead of the grip speed reads the same values: the shipped
  table's velocity rows are equal, checked), a sum of N positive terms within N u: (N + 8) u F.
- the pull force: an FE code's pull on the strip is the friction its contact carries, 2 F (two faces). The model's
  pull force also holds what no friction routine carries: its bar's dynamics and the contact weights its implicit step
  holds from the interval's start (the routine is given their mean over the interval). The test takes that part from
  the model itself, D = |pull - 2 sum_i T_i A_i(start)|, with T_i the interval's friction limits and A_i(start) the
  contact areas at the interval's start, and the shift of the areas E = 2 |sum_i T_i (A_i(start) - A_i(mean))|, and
  checks |pull - 2 F| <= D + E + 16 u pull once the draw is steady (after its first 20 ms).

With the default zeta = 0.2 the model carries the tool's share of the debris from node to node; a point's own state
cannot: the test prints the difference (``pytest -s``) and checks the conservation that holds all the same (the
transport conserves sum(beta), so the routine's total debris is the model's).
"""

from __future__ import annotations

import math
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tribocosim.components.friction_export.exported_law import load_law
from tribocosim.components.friction_export.named_calibration import DEFAULT as DEFAULT_CALIBRATION
from tribocosim.components.stripdraw import StripDrawModel, StripDrawParameters, make_friction_law, read_table
from tribocosim.cosim.apps.export_cli import main as export_main
from tribocosim.paths import DEFAULT_TABLE

HARNESS = Path(__file__).with_name("fe_harness")
U = 2.0**-53
GFORTRAN = shutil.which("gfortran")
needs_gfortran = pytest.mark.skipif(GFORTRAN is None, reason="gfortran is not installed (.ci/run installs it)")
FFLAGS = ["-O2", "-Wall", "-Werror", "-Wno-unused-dummy-argument"]
#: the unused dummy arguments are the FE codes' (temperatures, coordinates, ...): the argument lists keep them


def _default_law():
    """The law a routine exports by default: the shipped table with the default calibration."""
    return load_law(calibration_path=DEFAULT_CALIBRATION)


def _zig_cc() -> list[str]:
    from tribocosim.components.native.toolchain.compiler import CFLAGS, zig_command

    return [*zig_command(), "-target", "x86_64-linux-gnu.2.17", *CFLAGS]


def _run(cmd, **kw) -> subprocess.CompletedProcess:
    p = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, **kw)
    assert p.returncode == 0, f"{' '.join(map(str, cmd))}\n{p.stdout[-2000:]}\n{p.stderr[-4000:]}"
    return p


def _export(fmt: str, out: Path, *args: str) -> Path:
    assert export_main([fmt, "-o", str(out), *args]) == 0
    return out


def _includes(folder: Path) -> None:
    """The include files of a double-precision Abaqus run: implicit real*8 and, for Abaqus/Explicit, nprecd = 2."""
    (folder / "vaba_param.inc").write_text("      implicit real*8 (a-h,o-z)\n      parameter (nprecd=2)\n")
    (folder / "aba_param.inc").write_text("      implicit real*8 (a-h,o-z)\n")


def _check_number(f_file: Path) -> int:
    import re

    return int(re.search(r"check number (\d+)", f_file.read_text()).group(1))


def _build(tmp: Path, fmt: str, harness: str, *args: str) -> tuple[Path, int]:
    """Export ``fmt`` into tmp, compile it (gfortran, the system C compiler) with the harness: the executable and the
    export's check number."""
    _includes(tmp)
    f = _export(fmt, tmp / f"{fmt}.f", *args)
    _run([GFORTRAN, *FFLAGS, "-I", tmp, "-c", f, "-o", tmp / f"{fmt}_f.o"])
    _run(["cc", "-std=c11", "-O2", "-Wall", "-Wextra", "-Werror", "-c", tmp / f"{fmt}.c", "-o", tmp / f"{fmt}_c.o"])
    exe = tmp / f"{harness}"
    _run([GFORTRAN, "-O2", "-Wall", "-Werror", HARNESS / f"{harness}.f90", tmp / f"{fmt}_f.o", tmp / f"{fmt}_c.o",
          "-lm", "-o", exe])
    return exe, _check_number(f)


# ------------------------------------------------------------------------------------------------ compiling
@needs_gfortran
@pytest.mark.parametrize("fmt", ["vfriction", "fric", "usrfrc"])
def test_each_routine_compiles_with_its_argument_list(tmp_path, fmt):
    """FILE.f with gfortran -Wall -Werror (the FE codes' unused arguments aside), FILE.c with zig cc under the
    project's flags and with the system cc -std=c11 -Wall -Wextra -Werror; the three files have FILE's stem, and the
    headers cite the argument lists' sources and the table's content hash."""
    _includes(tmp_path)
    f = _export(fmt, tmp_path / "routine.f")
    assert sorted(p.name for p in tmp_path.glob("routine.*")) == ["routine.c", "routine.f", "routine.h"]
    _run([GFORTRAN, *FFLAGS, "-I", tmp_path, "-c", f, "-o", tmp_path / "f.o"])
    _run([*_zig_cc(), "-c", tmp_path / "routine.c", "-o", tmp_path / "zig.o"])
    _run(["cc", "-std=c11", "-O2", "-Wall", "-Wextra", "-Werror", "-c", tmp_path / "routine.c", "-o", tmp_path / "c.o"])
    digest = read_table(DEFAULT_TABLE).metadata["content_hash"]
    for path in tmp_path.glob("routine.*"):
        text = path.read_text()
        assert digest in text.replace("\nC     ", "").replace("\n *   ", ""), path
    text = f.read_text()
    expected = {"vfriction": ("VFRICTION", "vaba_param.inc", "USER=FRICTION, DEPVAR=3, PROPERTIES=1"),
                "fric": ("FRIC", "aba_param.inc", "*FRICTION, USER, DEPVAR=3, PROPERTIES=1"),
                "usrfrc": ("UNVERIFIED", "tcdynafric", "*USER_INTERFACE_FRICTION")}[fmt]
    for what in expected:
        assert what in text.replace("\nC     ", " "), what
    assert all(len(line) <= 72 for line in text.splitlines() if not line.startswith("C")), "fixed form: 72 columns"


def test_the_embedded_table_is_the_fmus_bit_for_bit(tmp_path):
    """mu and the cap of beta from the routine's constant table (the generated FILE.c, one translation unit with a C
    main) against the native core's table made from the table file (what the FMU reads), at points inside, on and
    outside the axes: equal to the last bit, with the same clamp flags."""
    _export("vfriction", tmp_path / "law.f", "--units", "SI")
    main = tmp_path / "main.c"
    main.write_text('#include <stdio.h>\n#include "law.c"\nint main(void) {\n    double p, v, b;\n'
                    "    tc_table_rows rows = {0};\n    const tc_node_law *law = &TRIBOCOSIM_LAW.law;\n"
                    '    while (scanf("%lf %lf %lf", &p, &v, &b) == 3) {\n        double mu, ac;\n'
                    "        unsigned char clamped = 0;\n        const tc_msg none = {NULL, 0};\n"
                    "        tc_law_mu(&law->p, law->table, p, 1, &v, &b, &mu, &clamped, &ac, &rows, none);\n"
                    '        printf("%a %a %d\\n", mu, tc_law_beta_cap(&law->p, law->table, p, v, &rows), clamped);\n'
                    "    }\n    return 0;\n}\n")
    exe = tmp_path / "main"
    _run(["cc", "-std=c11", "-O2", "-I", tmp_path, main, "-lm", "-o", exe])
    rng = np.random.default_rng(7)
    p = np.r_[np.exp(rng.uniform(np.log(0.5e6), np.log(40e6), 400)), read_table(DEFAULT_TABLE).pressure]
    v = rng.uniform(0, 0.7, p.size)
    b = rng.uniform(0, 1.1, p.size)
    out = _run([exe], input="".join(f"{float(x)!r} {float(y)!r} {float(z)!r}\n" for x, y, z in zip(p, v, b))).stdout.split("\n")
    law = _default_law()
    mu, flagged = law.mu(p, v, b)
    got = [line.split() for line in out if line]
    assert len(got) == p.size
    np.testing.assert_array_equal([float.fromhex(g[0]) for g in got], mu)
    np.testing.assert_array_equal([g[2] == "1" for g in got], flagged)
    np.testing.assert_array_equal([float.fromhex(g[1]) for g in got], [law.cap(x, y) for x, y in zip(p, v)])


# ------------------------------------------------------------------------------------------------ the replay
def _draw(zeta: float):
    """The model's draw with the law a routine exports by default (the default calibration's scale) at 10 MPa, 0.08
    m/s, 1 ms steps (one coupling interval each: a step slides 0.08 mm, below the interval's window_courant elements),
    with the increments of each node under the pad: its contact area (the interval's mean contact weight times l_e
    w_T), its slide w |dU| and what the model's interval held."""
    params = StripDrawParameters(zeta=zeta, particle_area_scale=_default_law().params.particle_area_scale)
    table = read_table(DEFAULT_TABLE)
    share = table.particle_area / table.contact_area  # the law's share at the table's nodes: the same at every velocity
    assert all(np.array_equal(share[:, j, :], share[:, 0, :]) for j in range(table.velocity.size))
    model = StripDrawModel(params, make_friction_law(params, table))
    pressure, v, dt = 10e6, 0.08, 1e-3
    fn, le, wt = params.normal_force(pressure), model.mesh.element_length, params.tool_width
    assert params.window_courant * le / v > dt  # one coupling interval per step
    steps = int(round(params.draw_length / v / dt))
    w0, u0, limits = model._nodal("contact_weight"), model.U, model.friction_limit
    increments, record = [], {"pull": [], "interval": [], "shift": [], "terms": [], "n_under": np.zeros(model.n_nodes)}
    for _ in range(steps):
        out = model.step(dt, {"normal_force": fn, "grip_velocity": v})
        w1, u1 = model._nodal("contact_weight"), model.U
        mean = 0.5 * (w0 + w1)
        under = np.nonzero(mean > 0)[0]
        areas = mean[under] * le * wt
        increments.append((under, pressure * areas, areas, mean[under] * np.abs(u1 - u0)[under]))
        record["pull"].append(out["pull_force"])
        record["interval"].append(float(np.sum(limits * w0 * le * wt)))
        record["shift"].append(float(np.sum(limits * (w0 - mean) * le * wt)))
        record["terms"].append((limits[under] * areas, under.size))
        record["n_under"][under] += 1
        w0, u0, limits = w1, u1, model.friction_limit
    return model, increments, record, dt


def _replay(exe: Path, tmp: Path, n_nodes: int, check: int, increments, dt: float):
    lines = [f"{n_nodes} 3 1", f"{check}."]
    for under, fn, area, slide in increments:
        lines.append(f"{dt!r} {under.size}")
        lines += [f"{i + 1} {float(f)!r} {float(a)!r} {float(s)!r} 0.0 0.0 1e300"
                  for i, f, a, s in zip(under, fn, area, slide)]
    path = tmp / "replay.txt"
    path.write_text("\n".join(lines) + "\n")
    out = _run([exe, path]).stdout.splitlines()
    forces = np.array([float(x.split()[1]) for x in out if x.startswith("F")])
    states = np.array([[float(y) for y in x.split()[2:]] for x in out if x.startswith("B")])
    return forces, states


@needs_gfortran
def test_vfriction_replays_the_strip_draw_models_pass(tmp_path):
    """beta per node, the friction force of every increment and the pull force of the replayed pass against the
    model's, within the tolerances the module docstring derives."""
    exe, check = _build(tmp_path, "vfriction", "vfriction_harness", "--units", "SI", "--set", "zeta=0")
    model, increments, rec, dt = _draw(zeta=0.0)
    forces, states = _replay(exe, tmp_path, model.n_nodes, check, increments, dt)
    beta = model.beta
    assert beta.max() > 0.05  # the pass makes debris: 35 mm of slide at 10 MPa
    bound = (2 * rec["n_under"] + 8) * U * beta
    np.testing.assert_array_less(np.abs(states[:, 0] - beta), bound + 1e-300)
    # state 2: the slide under the pad; state 3: no lookup left the table (10 MPa, beta below the simulated levels)
    slides = np.zeros(model.n_nodes)
    for under, _, _, slide in increments:
        slides[under] += slide
    np.testing.assert_allclose(states[:, 1], slides, rtol=1e-12, atol=0)
    assert np.all(states[:, 2] == 0)
    for k, (terms, n) in enumerate(rec["terms"][1:], start=1):  # the state before the first step is at P = 0
        total = float(np.sum(terms))
        assert abs(forces[k] - total) <= (n + 8) * U * total, k
    pull = np.array(rec["pull"])
    model_part = np.abs(pull - 2 * np.array(rec["interval"]))
    shift = 2 * np.abs(np.array(rec["shift"]))
    steady = slice(20, None)
    diff = np.abs(pull - 2 * forces)
    assert np.all(diff[steady] <= (model_part + shift + 16 * U * pull)[steady])
    print(f"\nzeta = 0: beta per node within {np.max(np.abs(states[:, 0] - beta) / np.maximum(beta, 1e-300)):.2g} "
          f"(relative; {np.sum(states[:, 0] == beta)} of {beta.size} nodes bit-identical); pull force 2 F of the routine "
          f"against the model's at the end of the pass: {(2 * forces[-1] - pull[-1]) / pull[-1]:+.3e} (relative), the "
          f"contact-area shift {shift[-1] / pull[-1]:.3e}, the model's own part {model_part[-1] / pull[-1]:.3e}")


@needs_gfortran
def test_the_default_zeta_moves_debris_a_point_state_cannot(tmp_path):
    """With zeta = 0.2 the model carries debris from node to node under the pad; the routine keeps it where it is made.
    Their totals are equal all the same (the transport conserves sum(beta), every source is the same): within the
    sum's rounding, 2 (n + 8) u per node summed; the per-node difference and the pull force's are printed."""
    exe, check = _build(tmp_path, "vfriction", "vfriction_harness", "--units", "SI")
    model, increments, rec, dt = _draw(zeta=0.2)
    forces, states = _replay(exe, tmp_path, model.n_nodes, check, increments, dt)
    beta = model.beta
    total = beta.sum()
    assert abs(states[:, 0].sum() - total) <= float(np.sum((2 * rec["n_under"] + 8) * U)) * beta.max() * 4
    rel = np.abs(states[:, 0] - beta).max() / beta.max()
    pull = np.array(rec["pull"])
    at_exit = np.argmax(beta)
    print(f"\nzeta = 0.2 (default): beta per node differs by up to {rel:.3f} of the largest beta ({beta.max():.4g} in "
          f"the model, {states[:, 0].max():.4g} in the routine; node {at_exit}: {beta[at_exit]:.4g} against "
          f"{states[at_exit, 0]:.4g}); sum of beta {total:.6g} against {states[:, 0].sum():.6g}; pull force 2 F against "
          f"the model's at the end of the pass: {(2 * forces[-1] - pull[-1]) / pull[-1]:+.3e} (relative)")
    assert rel > 1e-3  # the transport moves debris: a point's state does not hold it


# ------------------------------------------------------------------------------------------------ FRIC and LS-DYNA
@needs_gfortran
def test_fric_sticks_elastically_then_slides_at_mu_p(tmp_path):
    """Abaqus/Standard FRIC at 10 MPa (mm-t-s): below the elastic slip tolerance the point sticks (TAU = k DGAM,
    DDTDDG = k I with k = mu p / (0.005 CHRLNGTH)); beyond it it slides at |TAU| = mu p along the slip, with the
    state updated by the Archard production K P |DGAM| / (H h_p); an open point stays open; a wrong check number
    stops the analysis."""
    exe, check = _build(tmp_path, "fric", "fric_harness")
    law = _default_law()
    prm = law.params
    mu = float(law.mu(10e6, 0.08, 0.0)[0])
    press, length, dtime = 10.0, 1.0, 1.0  # MPa, mm, s
    k = mu * press / (0.005 * length)

    def call(lm, dgam, tau=(0.0, 0.0), props=(float(check),), statev=(0.0, 0.0, 0.0)):
        text = (f"{lm} {press} {dgam[0]} {dgam[1]} {dtime} {length} {tau[0]} {tau[1]} {len(statev)}\n"
                f"{' '.join(map(str, statev))} {len(props)}\n{' '.join(map(str, props))}\n")
        p = subprocess.run([str(exe)], input=text, capture_output=True, text=True)
        return p, (np.array([float(x) for x in p.stdout.split()]) if p.returncode == 0 else None)

    _, stick = call(1, (0.001, 0.0))
    assert stick[0] == 0
    np.testing.assert_allclose(stick[1:3], [k * 0.001, 0.0], rtol=1e-12)
    np.testing.assert_allclose(stick[3:7], [k, 0.0, 0.0, k], rtol=1e-12)
    dg = np.array([0.03, 0.04])  # 0.05 mm, beyond the 0.005 mm tolerance
    _, slide = call(0, dg)
    np.testing.assert_allclose(slide[1:3], mu * press * dg / 0.05, rtol=1e-12)
    np.testing.assert_allclose(slide[7:9], mu * dg / 0.05, rtol=1e-12)
    q = prm.archard_k * 10e6 / (prm.hardness * prm.particle_thickness)
    np.testing.assert_allclose(slide[9:12], [q * 0.05e-3, 0.05, 0.0], rtol=1e-12)
    _, opened = call(2, dg)
    assert opened[0] == 2 and np.all(opened[1:3] == 0)
    refused, _ = call(0, dg, props=(1.0,))
    assert refused.returncode == 3 and "check number" in refused.stdout


@needs_gfortran
def test_lsdyna_node_routine_returns_mu_as_its_coefficients(tmp_path):
    """tcdynafric at one node (mm-t-s): fric = (mu, mu, 0, 0) with mu at P = F_N / A and the node's beta at the
    increment's start; the history variables updated as the other routines' states."""
    exe, check = _build(tmp_path, "usrfrc", "usrfrc_harness")
    law = _default_law()
    beta0 = 0.05
    text = f"350.0 35.0 0.06 0.08 0.0 0.001 3\n{beta0} 1.0 0.0 1\n{check}.\n"  # 10 MPa, |ds| = 0.1 mm
    out = np.array([float(x) for x in _run([exe], input=text).stdout.split()])
    mu = float(law.mu(10e6, 0.1, beta0)[0])
    assert math.isclose(out[0], mu, rel_tol=8 * U) and out[1] == out[0] and out[2] == 0 and out[3] == 0
    prm = law.params
    assert math.isclose(out[4], beta0 + prm.archard_k * 10e6 * 1e-4 / (prm.hardness * prm.particle_thickness),
                        rel_tol=1e-12)
    assert math.isclose(out[5], 1.1, rel_tol=1e-12) and out[6] == 0


@needs_gfortran
def test_vfriction_stops_on_a_wrong_check_number_or_too_few_states(tmp_path):
    """The deck's property 1 must be the export's check number and DEPVAR at least 2: else the routine names the
    problem and calls XPLB_EXIT (the harness's exits with 3)."""
    exe, check = _build(tmp_path, "vfriction", "vfriction_harness", "--units", "SI")
    for head, what in ((f"2 3 1\n{check + 1}.\n", "check number"), (f"2 1 1\n{check}.\n", "fewer than 2 state")):
        path = tmp_path / "bad.txt"
        path.write_text(head + "0.001 1\n1 1.0 1.0 0.001 0.0 0.0 1e300\n")
        p = subprocess.run([str(exe), str(path)], capture_output=True, text=True)
        assert p.returncode == 3 and what in p.stdout, p.stdout


# ------------------------------------------------------------------------------------------------ the command
@pytest.mark.parametrize("args, named", [
    (["--beta", "0.1"], "--beta"),
    (["--passes", "2", "--pressure", "25"], "--passes"),
    (["--band", "2"], "--band"),
    (["--pressure-range", "2", "20"], "--pressure-range"),
    (["--units", "inch"], "--units"),
    (["--set", "no_such=1"], "--set"),
    (["--set", "mu0=-1"], "mu0"),
    (["--table", "missing.npz"], "missing.npz"),
])
def test_bad_input_is_one_line_exit_2_and_no_file(tmp_path, capsys, args, named):
    """Refused as the table exports refuse: one line on stderr naming the option, exit code 2, no file written."""
    out = tmp_path / "routine.f"
    assert export_main(["vfriction", "-o", str(out), *args]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and named in err, err
    assert not list(tmp_path.iterdir())


def test_the_routine_file_must_be_fortran_and_its_folder_exist(tmp_path, capsys):
    for target, named in ((tmp_path / "routine.k", ".f"), (tmp_path / "nowhere" / "routine.f", "does not exist")):
        assert export_main(["fric", "-o", str(target)]) == 2
        assert named in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


def test_the_routines_take_the_exports_law_options(tmp_path):
    """--set and --units reach the routine's law: the parameters and the units it embeds are those given."""
    from tribocosim.components.friction_export.table_source import c_double

    _export("fric", tmp_path / "a.f", "--set", "archard_k=2e-4", "--units", "SI")
    text = (tmp_path / "a.c").read_text()
    assert f".archard_k = {c_double(2e-4)}" in text and f".pressure_scale = {c_double(1.0)}" in text
    assert "archard_k=0.0002" in (tmp_path / "a.f").read_text()


def test_the_amalgamation_refuses_a_static_name_of_two_sources(monkeypatch):
    from tribocosim.components.friction_export import c_amalgamation

    monkeypatch.setattr(c_amalgamation, "SOURCES", ("core/tc_friction.c", "core/tc_friction.c"))
    with pytest.raises(c_amalgamation.AmalgamationError, match="defined in core/tc_friction.c"):
        c_amalgamation.source_text()


def test_c_double_literals_are_exact():
    from tribocosim.components.friction_export.table_source import c_double

    for x in (0.1, 1e-300, 5e-324, 12250.0 / 0.035**2, -2.5):
        assert float.fromhex(c_double(x)) == x
    assert c_double(math.inf) == "HUGE_VAL"


if __name__ == "__main__":  # pragma: no cover
    sys.exit(pytest.main([__file__, "-s"]))
