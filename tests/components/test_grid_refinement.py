"""The export's grid: the multilinear reading of the FE codes, and the refinement that makes it reproduce a function
within a tolerance, checked on closed forms (an exactly multilinear function, a function linear in one axis, the
h^2 convergence of linear interpolation)."""

from __future__ import annotations

import numpy as np
import pytest

from tribocosim.components.friction_export.grid_refinement import AxisSpec, multilinear, relative_deviation, sample


def test_multilinear_reproduces_a_multilinear_function_and_holds_the_ends():
    x, y = np.array([1.0, 2.0, 5.0]), np.array([0.0, 0.5, 3.0, 4.0])
    f = lambda a, b: 2.0 + 0.5 * a - 1.5 * b + 0.25 * a * b  # noqa: E731 - bilinear: reproduced exactly
    values = f(*np.meshgrid(x, y, indexing="ij"))[..., None]
    rng = np.random.default_rng(1)
    a, b = rng.uniform(1, 5, 500), rng.uniform(0, 4, 500)
    np.testing.assert_allclose(multilinear((x, y), values, (a, b))[:, 0], f(a, b), rtol=1e-13)
    # beyond the axes: the end values (clamped in each coordinate)
    np.testing.assert_allclose(multilinear((x, y), values, (np.array([0.0, 9.0]), np.array([-1.0, 7.0])))[:, 0],
                               [f(1.0, 0.0), f(5.0, 4.0)], rtol=1e-14)


def _exp_sampling(tol, seed=0):
    spec = [AxisSpec("x", (0.0, 3.0))]
    return sample(lambda p: np.exp(p[0])[..., None], spec, tol, 1e-3, seed)


def test_the_sampled_grid_reproduces_the_function_within_the_tolerance_on_an_independent_dense_check():
    s = _exp_sampling(0.005)
    assert s.reached and s.accuracy <= 0.005
    x = np.linspace(0.0, 3.0, 100_001)
    dense = relative_deviation(np.interp(x, s.axes[0], s.values[:, 0]), np.exp(x), 1e-3).max()
    assert dense <= 0.005
    assert dense == pytest.approx(s.accuracy, rel=0.05), "the stated accuracy is the largest deviation"


def test_linear_interpolation_needs_nodes_like_tolerance_to_the_minus_one_half():
    """The error of linear interpolation is h^2 f''/8: halving the tolerance takes sqrt(2) times the nodes."""
    tols = np.array([4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4])
    nodes = np.array([_exp_sampling(t).axes[0].size for t in tols], dtype=float)
    slope = np.polyfit(np.log(tols), np.log(nodes), 1)[0]
    assert -0.6 < slope < -0.4, slope


def test_an_axis_the_function_is_linear_in_keeps_its_nodes():
    specs = [AxisSpec("p", (1.0, 30.0), geometric=True), AxisSpec("v", (0.0, 0.5))]
    s = sample(lambda p: (np.log(p[0]) + 2.0 + p[1])[..., None], specs, 0.001, 1e-3)
    assert s.reached
    assert s.axes[1].tolist() == [0.0, 0.5]
    assert s.axes[0].size > 2
    assert np.all(np.diff(s.axes[0]) > 0) and s.axes[0][0] == 1.0 and s.axes[0][-1] == 30.0


def test_an_axis_not_refined_keeps_its_nodes_and_the_accuracy_says_what_that_costs():
    specs = [AxisSpec("x", (0.0, 1.0, 3.0), refine=False)]
    s = sample(lambda p: np.exp(p[0])[..., None], specs, 0.005, 1e-3)
    assert s.axes[0].tolist() == [0.0, 1.0, 3.0]
    assert not s.reached and s.accuracy > 0.1  # exp between 1 and 3 read linearly: far above the tolerance


def test_several_functions_share_one_grid_and_the_largest_deviation_counts():
    specs = [AxisSpec("x", (0.0, 3.0))]
    one = sample(lambda p: np.exp(p[0])[..., None], specs, 0.005, 1e-3)
    two = sample(lambda p: np.stack([np.exp(p[0]), np.exp(2 * p[0])], axis=-1), specs, 0.005, 1e-3)
    assert two.axes[0].size > one.axes[0].size and two.reached


def test_a_kink_across_the_range_stops_the_refinement_at_the_check_budget_and_the_accuracy_says_so():
    """mu clipped at 0 along a surface across the range (the paper's frictionless flakes at a high debris share): no
    grid of finite nodes reads the kink within 0.5 % of a floor of 1e-3, so the refinement would fill every axis
    with nodes along it (400 per axis: 1600^3 check points, gigabytes). It stops where a split would take the check's
    tensor grid past MAX_CHECK_POINTS, and the accuracy reached, above the tolerance, is what it states."""
    from tribocosim.components.friction_export import grid_refinement as gr

    specs = [AxisSpec("p", (1.0, 30.0), geometric=True), AxisSpec("v", (0.0, 0.5)), AxisSpec("beta", (0.0, 0.3))]

    def law(p):  # 0.15 (1 - 2 s), s growing with all three, clipped at 0 where s > 1/2
        share = 0.02 * np.log(p[0]) + 0.4 * p[1] + 2.0 * p[2]
        return (0.15 * np.maximum(0.0, 1.0 - 2.0 * share))[..., None]

    s = sample(law, specs, 0.005, 1e-3)
    assert gr._check_size(list(s.axes)) <= gr.MAX_CHECK_POINTS
    assert not s.reached and s.accuracy > 0.005, "the kink is not read within the tolerance, and the grid says so"
    assert s.values.shape == tuple(a.size for a in s.axes) + (1,)
