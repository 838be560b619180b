"""The native core library behind the Python models (components/native/toolchain/library.py): built from the FMUs' sources
into the cache, found there by a digest of what it is made of, and a clear error when it cannot be built."""

from __future__ import annotations

import pytest

from tribocosim.components.native.toolchain import compiler, library


def test_a_library_that_cannot_be_built_says_what_failed(tmp_path, monkeypatch):
    def no_compiler():
        raise compiler.CompileError("the C compiler package 'ziglang' is not installed (pip install ziglang)")

    monkeypatch.setattr(compiler, "zig_command", no_compiler)
    with pytest.raises(library.CoreBuildError, match="native core library cannot be built: the C compiler package "
                                                     "'ziglang' is not installed"):
        library.build(tmp_path / "libtc_core.so")
    assert not (tmp_path / "libtc_core.so").exists() and list(tmp_path.iterdir()) == [], "nothing left behind"


def test_the_cached_library_is_keyed_by_its_sources(tmp_path, monkeypatch):
    monkeypatch.setenv("TRIBOCOSIM_CACHE", str(tmp_path))
    path = library.library_path()
    assert path.parent == tmp_path / "core" and library.digest()[:20] in path.name and path.is_file()
    assert library.library_path() == path, "found, not built again"


def test_the_digest_covers_where_a_generated_constant_is_defined():
    """The parameter headers carry constants defined in Python (Native.constants: TC_STRIPDRAW_MU_FLOOR from
    friction_floor.MU_FLOOR); the files the digest reads without importing a component hold the declaration and the
    module that defines the value, so that a changed value builds a new library."""
    from pathlib import Path

    from tribocosim.components.stripdraw import component, friction_floor

    assert [c[0] for c in component.COMPONENT.native.constants] == ["mu_floor"]
    files = library.declaration_files(compiler.NATIVE_DIR.parent)
    assert {Path(component.__file__), Path(friction_floor.__file__)} <= files


@pytest.fixture(scope="module")
def few_newton_iterations(tmp_path_factory):
    """``build(max_iter) -> Core``: the core library with the generalized-alpha step's Newton iterations limited
    (-DTC_STRIPDRAW_NEWTON_MAX_ITER), so that the step halving runs."""
    cores = {}

    def build(max_iter: int) -> library.Core:
        if max_iter not in cores:
            path = tmp_path_factory.mktemp(f"newton{max_iter}") / "libtc_core.so"
            cores[max_iter] = library.Core(library.build(path, [f"TC_STRIPDRAW_NEWTON_MAX_ITER={max_iter}"]))
        return cores[max_iter]

    return build


def _draw_on(core, monkeypatch, steps: int):
    from tribocosim.components.stripdraw import StripDrawModel, StripDrawParameters, make_friction_law
    from tribocosim.components.stripdraw import friction, model

    for module in (friction, model):
        monkeypatch.setattr(module, "core", lambda: core)
    p = StripDrawParameters(friction_model="closed_form", draw_length=0.02, n_elements=60)
    m = StripDrawModel(p, make_friction_law(p))
    outs = [m.step(1e-3, {"normal_force": 12250.0, "grip_velocity": 0.08 * min(1.0, (k + 0.5) / 10)})
            for k in range(steps)]
    return m, outs


def test_a_step_whose_newton_iteration_stalls_is_halved(few_newton_iterations, monkeypatch):
    """Three Newton iterations per try: the steps that need more are halved (each half an exact generalized-alpha
    step of its own), so the draw ends close to the full solve's."""
    _, halved = _draw_on(few_newton_iterations(3), monkeypatch, 120)
    _, full = _draw_on(library.core(), monkeypatch, 120)
    assert halved[-1]["pull_force"] == pytest.approx(full[-1]["pull_force"], rel=1e-3)
    assert any(h["pull_force"] != f["pull_force"] for h, f in zip(halved, full)), "some step was halved"


def test_a_step_that_cannot_converge_is_refused_with_the_state_unchanged(few_newton_iterations, monkeypatch):
    from tribocosim.errors import ConvergenceError

    m2, _ = _draw_on(few_newton_iterations(0), monkeypatch, 0)  # no iteration allowed: it fails after 12 halvings
    before = m2.get_state()
    with pytest.raises(ConvergenceError, match="did not converge .* halved 12 times"):
        m2.step(1e-3, {"normal_force": 12250.0, "grip_velocity": 0.08})
    assert (m2.get_state() == before).all()


@pytest.mark.parametrize("settings", [{}, {"n_elements": 451, "debris_sink_length": 0.01},
                                      {"friction_velocity": "slip_rate", "internal_step": 2.5e-4},
                                      {"n_elements": 7, "rho_inf": 1.0}])
def test_the_avx_kernels_give_the_baseline_numbers_bit_for_bit(settings, tmp_path_factory, monkeypatch):
    """On a processor with AVX the bar's per-step kernels and its implicit step run as compiled for it
    (components/native/core/tc_step_kernels_avx.c: the same C in four-double registers); a build with -DTC_NO_AVX runs the
    baseline's (SSE2). The same arithmetic in wider registers: every output of every step and the whole state at the
    end (displacements, velocities, accelerations, plastic slip, debris, forces) the same bits, on meshes whose node
    counts leave every remainder of the four-wide loops."""
    import numpy as np

    import tribocosim
    from tribocosim.components.stripdraw import (StripDrawModel, StripDrawParameters, friction, make_friction_law, model,
                                                 read_table)

    avx = library.core()
    if not avx.lib.tc_step_kernels_avx_chosen():
        pytest.skip("this processor (or its operating system) does not run AVX: only the baseline is chosen here")
    path = tmp_path_factory.getbasetemp() / "no_avx" / "libtc_core.so"
    baseline = library.Core(path if path.is_file() else library.build(path, ["TC_NO_AVX"]))
    assert baseline.lib.tc_step_kernels_avx_chosen() == 0

    def draw(core):
        for module in (friction, model, library):  # the table's handle is made by library.core()
            monkeypatch.setattr(module, "core", lambda: core)
        p = StripDrawParameters(draw_length=0.03, **settings)
        m = StripDrawModel(p, make_friction_law(p, read_table(tribocosim.DEFAULT_TABLE)))
        outs = [m.step(1e-3, {"normal_force": 12250.0, "grip_velocity": 0.08 * min(1.0, (k + 0.5) / 20)})
                for k in range(300)]
        return outs, m.get_state()

    outs_avx, state_avx = draw(avx)
    outs_base, state_base = draw(baseline)
    assert outs_avx == outs_base
    assert np.array_equal(state_avx, state_base)
    assert outs_avx[-1]["pull_force"] > 0 and outs_avx[-1]["beta_max"] > 0, "the draw slid and made debris"
