"""Tests of cosim.engine.graph: SCCs against a reachability oracle, Gauss-Seidel order, algebraic loops."""

import itertools

import numpy as np

from tribocosim.cosim.engine.graph import algebraic_loops, evaluation_order, gauss_seidel_order, strongly_connected


def _reach(n, edges):
    r = np.eye(n, dtype=bool)
    for a, b in edges:
        r[a, b] = True
    for k in range(n):
        r |= r[:, [k]] & r[[k], :]
    return r


def test_strongly_connected_matches_reachability_oracle():
    rng = np.random.default_rng(7)
    for trial in range(30):
        n = int(rng.integers(1, 9))
        edges = [(int(a), int(b)) for a, b in rng.integers(0, n, size=(int(rng.integers(0, 15)), 2))]
        comps = strongly_connected(n, edges)
        r = _reach(n, edges)
        assert sorted(i for c in comps for i in c) == list(range(n)), "every node in exactly one component"
        for c in comps:
            for a, b in itertools.product(c, c):
                assert r[a, b], f"trial {trial}: {a},{b} in one component must reach each other"
        pos = {i: k for k, c in enumerate(comps) for i in c}
        for a, b in edges:
            assert pos[a] <= pos[b], f"trial {trial}: edge {a}->{b} points backwards in the topological order"
        for c1, c2 in itertools.combinations(comps, 2):
            assert not (r[c1[0], c2[0]] and r[c2[0], c1[0]]), "distinct components are not mutually reachable"


def test_gauss_seidel_order_of_a_chain_and_of_a_two_way_coupling():
    chain = gauss_seidel_order(3, [(2, 1), (1, 0)])
    assert chain.order == (2, 1, 0) and not chain.backward and not chain.cycles
    cyc = gauss_seidel_order(2, [(1, 0), (0, 1), (0, 1)])
    assert cyc.order == (0, 1) and cyc.backward == frozenset({0}) and cyc.cycles == ((0, 1),)
    forced = gauss_seidel_order(2, [(1, 0), (0, 1)], preferred=[1, 0])
    assert forced.order == (1, 0) and forced.backward == frozenset({1})


def test_algebraic_loop_contraction_is_sqrt_of_loop_gain_for_a_two_cycle():
    g1, g2 = 0.9, 1.1
    dep = np.array([[False, True], [True, False]])
    jac = np.array([[0.0, g1], [g2, 0.0]])
    loops = algebraic_loops(dep, jac)
    assert len(loops) == 1 and loops[0].links == (0, 1)
    np.testing.assert_allclose(loops[0].contraction**2, g1 * g2, rtol=1e-12, err_msg="rho^2 = |loop gain|")
    assert algebraic_loops(np.zeros((2, 2), dtype=bool), np.zeros((2, 2))) == []


def test_evaluation_order_follows_feedthrough():
    # links: 0: inst0 -> inst1 (inst1 output (link 1) depends on it), 1: inst1 -> inst2
    links = [(0, 1), (1, 2)]
    dep = np.array([[False, False], [True, False]])
    assert evaluation_order(3, links, dep) == [0, 1, 2]


def test_evaluation_order_inside_a_two_way_coupling_puts_the_feedthrough_instance_last():
    # inst0 <-> inst1; only inst0's output depends on its input (link 1 -> inst0 feeds link 0's source)
    links = [(0, 1), (1, 0)]
    dep = np.array([[False, True], [False, False]])
    assert evaluation_order(2, links, dep) == [1, 0]
