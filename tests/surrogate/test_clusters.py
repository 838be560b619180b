"""Contact clusters (periodic labelling, areas, border distances) and summit counts."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tribocosim.errors import ParameterError
from tribocosim.surrogate.clusters import cluster_statistics, contact_clusters, count_summits


def _mask(n, *blocks):
    m = np.zeros((n, n), dtype=bool)
    for r0, r1, c0, c1 in blocks:
        m[r0:r1, c0:c1] = True
    return m


def test_clusters_touching_across_the_boundary_are_one():
    m = _mask(16, (0, 1, 0, 1), (0, 1, 15, 16))  # (0,0) and (0,15): neighbours through the edge
    assert contact_clusters(m)[1] == 1 and contact_clusters(m, periodic=False)[1] == 2
    corners = _mask(16, (0, 1, 0, 1), (0, 1, 15, 16), (15, 16, 0, 1), (15, 16, 15, 16))
    labels, count = contact_clusters(corners)
    assert count == 1 and set(np.unique(labels)) == {0, 1}
    stats = cluster_statistics(corners, size=16.0)
    assert_allclose(stats["areas"], [4.0], rtol=0, err_msg="one cluster of 4 pixels")
    assert math.isnan(stats["mean_cluster_distance"]), "d_c undefined for a single cluster"


def test_connectivity_four_versus_eight():
    diag = _mask(8, (2, 3, 2, 3), (3, 4, 3, 4))
    assert contact_clusters(diag, connectivity=4)[1] == 2
    assert contact_clusters(diag, connectivity=8)[1] == 1
    wrap = _mask(8, (0, 1, 0, 1), (7, 8, 7, 8))  # diagonal through the corner of the torus
    assert contact_clusters(wrap, connectivity=8)[1] == 1
    assert contact_clusters(wrap, connectivity=4)[1] == 2
    assert_allclose(cluster_statistics(wrap, 8.0)["mean_cluster_distance"], math.sqrt(2),
                    rtol=1e-12, err_msg="corner-touching clusters are sqrt(2) dx apart")


def test_border_distances_on_a_hand_made_map():
    # n = 20, dx = 1: A rows 2-4 x cols 2-4, B rows 2-4 x cols 10-12, C rows 12-14 x cols 2-4
    m = _mask(20, (2, 5, 2, 5), (2, 5, 10, 13), (12, 15, 2, 5))
    stats = cluster_statistics(m, size=20.0)
    assert stats["n_clusters"] == 3
    assert_allclose(stats["areas"], [9.0, 9.0, 9.0], rtol=0, err_msg="3x3 clusters")
    # A-B 6 (cols 4 -> 10), A-C 8 (rows 4 -> 12), B-C 10 (8 rows, 6 cols): minima 6, 6, 8
    assert_allclose(np.sort(stats["min_distances"]), [6.0, 6.0, 8.0], rtol=1e-12,
                    err_msg="minimum border-to-border distances")
    assert_allclose(stats["mean_cluster_distance"], 20.0 / 3.0, rtol=1e-12, err_msg="d_c")


def test_border_distance_through_the_periodic_boundary():
    # A cols 2-4 and B cols 15-17 on n = 20: 11 apart inside, 5 through the edge
    m = _mask(20, (2, 5, 2, 5), (2, 5, 15, 18))
    assert_allclose(cluster_statistics(m, 20.0)["mean_cluster_distance"], 5.0, rtol=1e-12,
                    err_msg="periodic minimum-image distance")
    assert_allclose(cluster_statistics(m, 20.0, periodic=False)["mean_cluster_distance"], 11.0,
                    rtol=1e-12, err_msg="non-periodic distance")
    assert_allclose(cluster_statistics(m, 2e-5)["mean_cluster_distance"], 5e-6, rtol=1e-12,
                    err_msg="distances scale with the pixel size")


def test_traction_and_mask_give_the_same_statistics():
    rng = np.random.default_rng(1)
    t = np.where(rng.random((32, 32)) < 0.1, rng.random((32, 32)), 0.0)
    a, b = cluster_statistics(t, 1e-4), cluster_statistics(t > 0, 1e-4)
    assert a["n_clusters"] == b["n_clusters"]
    assert_allclose(a["areas"].sum(), np.count_nonzero(t) * (1e-4 / 32) ** 2, rtol=1e-12,
                    err_msg="cluster areas add up to the contact area")


def test_poisson_clusters_follow_clark_evans():
    # isolated pixels scattered uniformly: mean nearest-neighbour distance L / (2 sqrt(N)) (App. E)
    n, count = 1024, 2000
    rng = np.random.default_rng(7)
    flat = rng.choice(n * n, size=count, replace=False)
    m = np.zeros(n * n, dtype=bool)
    m[flat] = True
    stats = cluster_statistics(m.reshape(n, n), size=1.0, connectivity=4)
    assert stats["n_clusters"] > 0.99 * count
    assert_allclose(stats["mean_cluster_distance"], 1.0 / (2.0 * math.sqrt(stats["n_clusters"])),
                    rtol=0.05, err_msg="Poisson nearest-neighbour distance")


@pytest.mark.parametrize("k", [1, 2, 3])
def test_summits_of_an_egg_box(k):
    n = 48
    x = np.arange(n) / n
    h = np.cos(2 * np.pi * k * x)[:, None] * np.cos(2 * np.pi * k * x)[None, :]
    assert count_summits(h) == 2 * k * k, "cos(kx) cos(ky) has 2 k^2 maxima per period"


def test_summit_on_the_corner_counts_once():
    n = 32
    d = np.minimum(np.arange(n), n - np.arange(n)).astype(float)
    h = np.exp(-(d[:, None] ** 2 + d[None, :] ** 2) / 8.0)  # one bump centred on (0, 0)
    assert count_summits(h) == 1
    assert count_summits(np.zeros((8, 8))) == 0


def test_bad_input():
    with pytest.raises(ParameterError, match="mask"):
        contact_clusters(np.zeros((4, 5), dtype=bool))
    with pytest.raises(ParameterError, match="connectivity"):
        contact_clusters(np.zeros((4, 4), dtype=bool), connectivity=6)
    with pytest.raises(ParameterError, match="size"):
        cluster_statistics(np.zeros((4, 4)), size=0.0)
