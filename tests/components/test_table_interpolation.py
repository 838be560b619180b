"""The friction table's lookups (components/native/core/tc_table_lookup.c, through FrictionTable.interpolate_array):
the monotone cubic interpolation of a version 4 table against a reference built on scipy's PCHIP, its properties
(nodes exact, monotone where the data are, no overshoot, third order on a smooth function, linear functions exact),
which nodes a lookup reads (the count of lookups that read an unsimulated node, with the exact round-off case of
a press), and the cap of beta (Eq. 24) found on the cubic pieces.
"""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.interpolate import CubicHermiteSpline, PchipInterpolator
from scipy.optimize import brentq

from tribocosim.components.stripdraw import StripDrawModel, make_friction_law
from tribocosim.components.stripdraw.parameters import StripDrawParameters
from tribocosim.components.stripdraw.table import READ_WEIGHT, FrictionTable

E = READ_WEIGHT


def make_table(pressure, velocity, beta, ap, ac=None, simulated=None, version=4) -> FrictionTable:
    """A table of the given A_p (A_c = 1 unless given) and simulated flags (all 1 unless given)."""
    ac = np.ones_like(ap) if ac is None else ac
    sim = np.ones_like(ap) if simulated is None else simulated
    z = np.zeros_like(ap)
    extras = {"simulated": sim, "contact_area_se": z, "particle_area_se": z, "particle_area_clusters": 0.5 * ap,
              "particle_area_clusters_se": z}
    if version == 4:
        extras["mu_se"] = z
    return FrictionTable(pressure, velocity, beta, 0.15 * np.maximum(0, 1 - ap / ac), {"beta_threshold": 1.0},
                         contact_area=ac, particle_area=ap, contact_area_std=z, particle_area_std=z, extras=extras)


# ---- a reference on scipy ------------------------------------------------------------------------------------


def _cell(axis, q):
    qc = min(max(q, axis[0]), axis[-1])
    if axis.size == 1:
        return 0, 0.0, qc
    i = min(int(np.searchsorted(axis, qc, side="right")) - 1, axis.size - 2)
    return i, (qc - axis[i]) / (axis[i + 1] - axis[i]), qc


def _slopes(x, y, u):
    """PCHIP slopes (scipy) of every node over the run of nodes of its kind (u), over the whole line for a node
    alone of its kind."""
    n = x.size
    d = np.zeros(n)
    for k in range(n):
        lo, hi = k, k
        while lo > 0 and u[lo - 1] == u[k]:
            lo -= 1
        while hi < n - 1 and u[hi + 1] == u[k]:
            hi += 1
        run = slice(lo, hi + 1) if hi > lo else slice(0, n)
        if x[run].size >= 2:
            d[k] = PchipInterpolator(x[run], y[run]).derivative()(x[k])
    return d


def _limit(d, m):
    """A slope limited to the square 0 <= d / m <= 3 of a piece's secant m."""
    return 0.0 if m == 0 or np.sign(d) != np.sign(m) else float(np.clip(d, -3 * abs(m), 3 * abs(m)))


def _hermite(x, y, d0, d1, q, limit):
    m = (y[1] - y[0]) / (x[1] - x[0])
    if limit:
        d0, d1 = _limit(d0, m), _limit(d1, m)
    return float(CubicHermiteSpline(x, y, [d0, d1])(q))


def _line(x, y, u, q, d):
    """One line at q: the Hermite piece with the slopes d, limited where the piece's nodes differ in kind."""
    i, t, qc = _cell(x, q)
    if x.size == 1:
        return y[0]
    return _hermite(x[i:i + 2], y[i:i + 2], d[i], d[i + 1], qc, u[i] != u[i + 1])


class Reference:
    """The values and the slopes along beta of every table row interpolated monotone cubic in ln P to the rows of the
    velocity cell, each row the Hermite pieces in beta of those (limited to the monotone square), linear in v; every
    slope a kind-wise PCHIP slope of scipy."""

    def __init__(self, table: FrictionTable, values):
        self.t, self.values = table, values
        self.u = u = 1.0 - table.array("simulated")
        self.x = x = np.log(table.pressure)
        nP, nv, nb = values.shape
        self.row_slopes = np.array([[_slopes(table.beta, values[i, j], u[i, j]) for j in range(nv)]
                                    for i in range(nP)])
        self.col = {(j, k): (_slopes(x, values[:, j, k], u[:, j, k]), _slopes(x, self.row_slopes[:, j, k], u[:, j, k]))
                    for j in range(nv) for k in range(nb)}

    def __call__(self, p, v, b) -> float:
        t, u, x = self.t, self.u, self.x
        lp = np.log(min(max(p, t.pressure[0]), t.pressure[-1]))
        iv, tv, _ = _cell(t.velocity, abs(v))
        ib, tb, bc = _cell(t.beta, b)
        rows = []
        for j in sorted({iv, min(iv + 1, t.velocity.size - 1)}):
            ys, ds = [], []
            for k in (ib, ib + 1):
                dy, dd = self.col[j, k]
                ys.append(_line(x, self.values[:, j, k], u[:, j, k], lp, dy))
                ds.append(_line(x, self.row_slopes[:, j, k], u[:, j, k], lp, dd))
            rows.append(_hermite(t.beta[ib:ib + 2], ys, ds[0], ds[1], bc, True))
        return rows[0] if len(rows) == 1 or tv == 0 else (1 - tv) * rows[0] + tv * rows[1]


def random_table(rng, monotone=False, mask="staircase") -> FrictionTable:
    P = np.array([1e6, 2e6, 5e6, 1e7, 2e7, 3e7])
    v = np.array([0.0, 0.08, 0.5])
    b = np.array([0.0, 0.02, 0.05, 0.1, 0.2, 0.3, 0.5, 0.75, 1.0])
    if monotone:  # increasing in beta from 0 on every row and in P on every column
        steps = np.sort(rng.uniform(0.0, 1.0, (6, 3, 9)), axis=0)  # each step along beta grows with P
        steps[:, :, 0] = 0.0
        ap = np.cumsum(steps, axis=2)
    else:
        ap = rng.uniform(0.0, 1.0, (6, 3, 9))
    ap = 0.9 * ap / ap.max()  # shares A_p / A_c (A_c = 1) below 1
    sim = np.ones_like(ap)
    if mask == "staircase":  # beta >= 0.5 below 10 MPa, 1.0 at 10 MPa not simulated (the shipped pattern)
        sim[:3, :, 6:] = 0.0
        sim[3, :, 8] = 0.0
    elif mask == "random":
        sim = (rng.uniform(size=ap.shape) > 0.3).astype(float)
    return make_table(P, v, b, ap, simulated=sim)


@pytest.mark.parametrize("mask", ["all", "staircase", "random"])
def test_the_native_lookup_is_the_reference(mask):
    rng = np.random.default_rng(11)
    t = random_table(rng, mask=mask)
    p = np.exp(rng.uniform(np.log(0.8e6), np.log(3.2e7), 300))
    v = rng.uniform(0.0, 0.6, 300)
    b = rng.uniform(0.0, 1.05, 300)
    ours = np.array([t.interpolate_array(t.particle_area, pk, vk, bk)[0] for pk, vk, bk in zip(p, v, b)])
    reference = Reference(t, t.particle_area)
    ref = np.array([reference(pk, vk, bk) for pk, vk, bk in zip(p, v, b)])
    assert_allclose(ours, ref, rtol=1e-11, atol=1e-14)
    # many queries at one pressure (the strip draw's call) give the same numbers as one query at a time
    many, _ = t.interpolate_array(t.particle_area, 7e6, v, b)
    one = np.array([t.interpolate_array(t.particle_area, 7e6, vk, bk)[0] for vk, bk in zip(v, b)])
    assert np.array_equal(many, one)


# ---- a reference that computes every slope at the query, in the native arithmetic ------------------------------


def _sgn(x: float) -> int:
    return int(x > 0) - int(x < 0)


def _kind_slope(x, y, u, k) -> float:
    """The slope at node k of the line (x, y) from its neighbours of its kind u (every neighbour for a node alone of
    its kind): the PCHIP formulas of tc_pchip.c, in its operation order."""
    n = len(x)
    if n < 2:
        return 0.0
    same = (lambda a: u is None or u[a] == u[k])
    left, right = k > 0 and same(k - 1), k + 1 < n and same(k + 1)
    if not left and not right:
        return _kind_slope(x, y, None, k)
    sec = (lambda a: (y[a + 1] - y[a]) / (x[a + 1] - x[a]))

    def end(h0, h1, m0, m1):
        d = ((2.0 * h0 + h1) * m0 - h0 * m1) / (h0 + h1)
        if _sgn(d) != _sgn(m0):
            return 0.0
        return 3.0 * m0 if _sgn(m0) != _sgn(m1) and abs(d) > 3.0 * abs(m0) else d

    if left and right:
        m0, m1 = sec(k - 1), sec(k)
        if _sgn(m0) != _sgn(m1) or m0 == 0.0 or m1 == 0.0:
            return 0.0
        h0, h1 = x[k] - x[k - 1], x[k + 1] - x[k]
        w1, w2 = 2.0 * h1 + h0, h1 + 2.0 * h0
        return (w1 + w2) / (w1 / m0 + w2 / m1)
    if right:
        if k + 2 < n and same(k + 2):
            return end(x[k + 1] - x[k], x[k + 2] - x[k + 1], sec(k), sec(k + 1))
        return sec(k)
    if k >= 2 and same(k - 2):
        return end(x[k] - x[k - 1], x[k - 1] - x[k - 2], sec(k - 1), sec(k - 2))
    return sec(k - 1)


def _limited(d, m) -> float:
    if m == 0.0 or _sgn(d) != _sgn(m):
        return 0.0
    return 3.0 * m if abs(d) > 3.0 * abs(m) else d


def _piece(x, y, u, k, t) -> float:
    """The Hermite piece from node k to k + 1 of a line at t, its node slopes limited where the kinds differ."""
    d0, d1 = _kind_slope(x, y, u, k), _kind_slope(x, y, u, k + 1)
    if u[k] != u[k + 1]:
        m = (y[k + 1] - y[k]) / (x[k + 1] - x[k])
        d0, d1 = _limited(d0, m), _limited(d1, m)
    return _hermite_at(y[k], y[k + 1], d0, d1, x[k + 1] - x[k], t)


def _hermite_at(y0, y1, d0, d1, h, t) -> float:
    s = 1.0 - t
    return (1.0 + 2.0 * t) * s * s * y0 + t * t * (3.0 - 2.0 * t) * y1 + h * t * s * (s * d0 - t * d1)


def direct_lookup(table: FrictionTable, values, p, v, b) -> float:
    """A version 4 lookup with every slope taken at the query from the table's nodes (the rows' slopes along beta,
    the columns' along ln P, the pieces' limits): what the native lookup computed at each call before its table kept
    the slopes, written out in Python floats."""
    u = 1.0 - table.array("simulated")
    x, beta = np.log(table.pressure).tolist(), table.beta.tolist()
    ip, tp, _ = _cell(np.log(table.pressure), float(np.log(min(max(p, table.pressure[0]), table.pressure[-1]))))
    iv, tv, _ = _cell(table.velocity, abs(float(v)))
    ib, tb, _ = _cell(table.beta, float(b))
    tp, tv, tb = float(tp), float(tv), float(tb)
    rows = []
    for j in (iv, iv + 1) if tv != 0.0 else (iv,):
        y, d = [], []
        slopes = [[_kind_slope(beta, values[i, j].tolist(), u[i, j].tolist(), k) for k in range(len(beta))]
                  for i in range(len(x))]
        for k in range(len(beta)):
            col, kinds = values[:, j, k].tolist(), u[:, j, k].tolist()
            if len(x) == 1:
                y.append(col[0])
                d.append(slopes[0][k])
                continue
            y.append(_piece(x, col, kinds, ip, tp))
            d.append(_piece(x, [s[k] for s in slopes], kinds, ip, tp))
        if len(beta) == 1:
            rows.append(y[0])
            continue
        m = (y[ib + 1] - y[ib]) / (beta[ib + 1] - beta[ib])
        rows.append(_hermite_at(y[ib], y[ib + 1], _limited(d[ib], m), _limited(d[ib + 1], m), beta[ib + 1] - beta[ib],
                                tb))
    return rows[0] if tv == 0.0 else (1.0 - tv) * rows[0] + tv * rows[1]


@pytest.mark.parametrize("mask", ["all", "staircase", "random"])
def test_the_kept_slopes_give_the_lookup_of_slopes_taken_at_each_query(mask):
    """The table keeps the slopes of its rows and columns (tc_table_cubic) and a lookup evaluates Hermite pieces only:
    the values and mu of the strip-draw law are those of the slopes taken at each query from the nodes (direct_lookup),
    to round-off (1e-14 of the largest value; a compiler that fuses multiply-adds rounds a few operations
    differently), over random queries, the pressure nodes, 12250 N on the 35 x 35 mm pad (just below 10 MPa) and the
    velocity nodes."""
    rng = np.random.default_rng(17)
    t = random_table(rng, mask=mask)
    p = np.concatenate([np.exp(rng.uniform(np.log(0.8e6), np.log(3.2e7), 160)), t.pressure, [12250 / 0.035 ** 2] * 4])
    v = np.concatenate([rng.uniform(0.0, 0.6, 160), rng.choice(t.velocity, 10)])
    b = rng.uniform(0.0, 1.05, 170)
    ours = np.array([t.interpolate_array(t.particle_area, *q)[0] for q in zip(p, v, b)])
    ref = np.array([direct_lookup(t, t.particle_area, *q) for q in zip(p, v, b)])
    assert_allclose(ours, ref, rtol=1e-14, atol=1e-14 * np.abs(t.particle_area).max())
    # the law reads the share the table keeps the slopes of (A_c = 1 here: the share is A_p)
    params = StripDrawParameters()
    law = make_friction_law(params, t)
    r = params.flake_shear_ratio  # mu = mu0 (1 - (1 - r) min(1, s q)): capped where flakes carry the whole contact
    mu_ref = np.array([params.mu0 * (1.0 - (1.0 - r) * min(1.0, params.particle_area_scale
                                                           * direct_lookup(t, t.particle_area, *q)))
                       for q in zip(p, v, b)])
    assert_allclose(law.mu(p, v, b)[0], mu_ref, rtol=1e-14, atol=1e-14 * params.mu0)


def test_rows_kept_between_lookups_change_no_number():
    """The strip-draw model keeps the interpolated rows of its last lookup (tc_table_rows) for the next at the same
    pressure and velocity cell (the friction limits, the cap of beta and the state's limits of an interval): lookups
    through one kept buffer, in an order that hits and misses it, give the numbers of lookups without it, bit for
    bit."""
    import ctypes

    from tribocosim.components.native.toolchain.library import UBYTE_P, core, ptr

    rng = np.random.default_rng(23)
    t = random_table(rng, mask="random")
    params = StripDrawParameters()
    law = make_friction_law(params, t)
    c = core()
    struct = c.struct(params)
    rows = ctypes.create_string_buffer(32768)  # zeroed, larger than tc_table_rows
    for _ in range(300):
        pk = float(rng.choice([*t.pressure, 3.3e6, 7.1e6]))
        v = np.full(12, rng.choice([0.0, 0.08, 0.2])) if rng.uniform() < 0.7 else rng.uniform(0, 0.6, 12)
        b = rng.uniform(0.0, 1.0, 12)
        kept, flags = np.empty(12), np.zeros(12, dtype=np.uint8)
        c.call(c.lib.tc_law_mu, ctypes.byref(struct), law.native_table, pk, 12, ptr(v), ptr(b), ptr(kept),
               ptr(flags, UBYTE_P), ptr(np.empty(12)), ctypes.cast(rows, ctypes.c_void_p))
        fresh, fresh_flags = law.mu(pk, v, b)
        assert np.array_equal(kept, fresh) and np.array_equal(flags.astype(bool), fresh_flags)
        vq = float(v[0])
        assert c.lib.tc_law_beta_cap(ctypes.byref(struct), law.native_table, pk, vq,
                                     ctypes.cast(rows, ctypes.c_void_p)) == law.beta_cap(pk, vq)


def test_continuous_across_the_nodes_where_the_simulated_levels_change():
    """At a pressure node whose row simulated more levels than the row below (the shipped staircase), and at every
    beta node, the value just below and just above the node is the node's value to within the slope times the step:
    the slopes along beta are interpolated in P, so no kink of the kinds makes a jump."""
    t = random_table(np.random.default_rng(6), monotone=True, mask="staircase")
    bq = np.linspace(0.0, 1.0, 401)
    for p in t.pressure[1:-1]:
        at = t.interpolate_array(t.particle_area, p, 0.08, bq)[0]
        for f in (1 - 1e-9, 1 + 1e-9):
            near = t.interpolate_array(t.particle_area, p * f, 0.08, bq)[0]
            assert np.max(np.abs(near - at)) < 1e-8, (p, f)


def test_every_node_is_reproduced_exactly():
    t = random_table(np.random.default_rng(2), mask="random")
    P, V, B = np.meshgrid(t.pressure, t.velocity, t.beta, indexing="ij")
    for name in ("particle_area", "contact_area", "mu", "particle_area_se"):
        out, _ = t.interpolate_array(t.array(name), P.ravel(), V.ravel(), B.ravel())
        assert np.array_equal(out.reshape(P.shape), t.array(name)), name


def test_monotone_where_the_data_are_and_no_overshoot():
    """Rows increasing in beta and columns increasing in P (with the shipped pattern of unsimulated nodes too): the
    interpolant increases along beta at every node pressure and along P at every node beta, and, for data of one
    shape at every pressure (A_p = a(P) g(beta)), along beta at every pressure; random data: every value lies within
    the values of its cell's corners."""
    rng = np.random.default_rng(5)
    bq = np.linspace(0.0, 1.0, 801)
    pq = np.geomspace(1e6, 3e7, 801)
    for mask in ("all", "staircase"):
        t = random_table(rng, monotone=True, mask=mask)
        for p in t.pressure:
            for v in (0.0, 0.05, 0.3, 0.5):
                out, _ = t.interpolate_array(t.particle_area, p, v, bq)
                assert np.all(np.diff(out) >= 0.0), (mask, p, v)
        for b in t.beta:
            out = np.array([t.interpolate_array(t.particle_area, p, 0.08, b)[0] for p in pq])
            assert np.all(np.diff(out) >= 0.0), (mask, b)
        shape = t.particle_area[-1:, :, :] * np.cumsum(rng.uniform(0.1, 1, 6))[:, None, None] / 6.0
        s = make_table(t.pressure, t.velocity, t.beta, shape, simulated=t.array("simulated"))
        for p in np.geomspace(1e6, 3e7, 37):
            out, _ = s.interpolate_array(s.particle_area, p, 0.08, bq)
            assert np.all(np.diff(out) >= -1e-15 * out.max()), (mask, p)
    t = random_table(rng, mask="random")
    for _ in range(2000):
        p, v, b = np.exp(rng.uniform(np.log(1e6), np.log(3e7))), rng.uniform(0, 0.5), rng.uniform(0, 1)
        out = t.interpolate_array(t.particle_area, p, v, b)[0]
        i = min(np.searchsorted(t.pressure, p, "right") - 1, 4)
        j = min(np.searchsorted(t.velocity, v, "right") - 1, 1)
        k = min(np.searchsorted(t.beta, b, "right") - 1, 7)
        corners = t.particle_area[i:i + 2, j:j + 2, k:k + 2]
        assert corners.min() - 1e-14 <= out <= corners.max() + 1e-14


def _smooth_table(n_pressure, n_beta, f):
    P = np.geomspace(1e6, 3e7, n_pressure)
    b = np.linspace(0.0, 1.0, n_beta)
    PP, _, BB = np.meshgrid(P, [0.0, 1.0], b, indexing="ij")
    return make_table(P, np.array([0.0, 1.0]), b, f(PP, BB))


@pytest.mark.parametrize("axis", ["pressure", "beta"])
def test_third_order_on_a_smooth_function(axis):
    """A_p = 0.01 (P / 10 MPa)^0.9 (smooth in ln P) and beta / (1 + 4 beta) (the saturating form): the largest error
    over 4000 points falls as h^3 (local order of the two finest grids above 2.7); a function linear in beta and in
    ln P is reproduced to round-off."""
    rng = np.random.default_rng(1)
    pq = np.exp(rng.uniform(np.log(1e6), np.log(3e7), 4000))
    bq = rng.uniform(0.0, 1.0, 4000)
    f = ((lambda P, b: 0.01 * (P / 1e7) ** 0.9 + 0 * b) if axis == "pressure" else (lambda P, b: b / (1 + 4 * b)))
    h, err = [], []
    for n in (9, 17, 33, 64):
        t = _smooth_table(n, 2, f) if axis == "pressure" else _smooth_table(2, n, f)
        err.append(np.max(np.abs(t.interpolate_array(t.particle_area, pq, 0.5, bq)[0] - f(pq, bq))))
        h.append(1.0 / (n - 1))
    order = np.diff(np.log(err)) / np.diff(np.log(h))
    assert order[-1] > 2.7, (err, order)
    lin = (lambda P, b: 0.3 + 0.2 * np.log(P / 1e6) + 0.5 * b)
    t = _smooth_table(7, 9, lin)
    assert_allclose(t.interpolate_array(t.particle_area, pq, 0.5, bq)[0], lin(pq, bq), rtol=1e-12)


# ---- which nodes a lookup reads ----------------------------------------------------------------------------


def _reads_unsimulated(t, p, v, b) -> bool:
    """The reference rule: a corner of the cell with a weight (the product of the local coordinates, ln P on the
    pressure axis of a version 4 table) above 1e-9 is not simulated."""
    x = np.log(t.pressure) if t.version == 4 else t.pressure
    ip, tp, _ = _cell(x, np.log(min(max(p, t.pressure[0]), t.pressure[-1])) if t.version == 4 else p)
    iv, tv, _ = _cell(t.velocity, abs(v))
    ib, tb, _ = _cell(t.beta, b)
    sim = t.array("simulated")
    for a, wa in ((0, 1 - tp), (1, tp)):
        for c, wc in ((0, 1 - tv), (1, tv)):
            for d, wd in ((0, 1 - tb), (1, tb)):
                if wa * wc * wd > E and sim[ip + a, iv + c, ib + d] == 0:
                    return True
    return False


@pytest.mark.parametrize("version", [3, 4])
def test_a_lookup_counts_when_it_reads_an_unsimulated_node(version):
    rng = np.random.default_rng(4)
    t = random_table(rng, mask="random")
    if version == 3:
        t = make_table(t.pressure, t.velocity, t.beta, t.particle_area, simulated=t.array("simulated"), version=3)
    p = np.exp(rng.uniform(np.log(0.9e6), np.log(3.1e7), 500))
    v, b = rng.uniform(0.0, 0.5, 500), rng.uniform(0.0, 1.0, 500)
    flags = np.array([t.interpolate_array(t.particle_area, *q)[1] for q in zip(p, v, b)])
    outside = (p < 1e6 * (1 - 1e-9)) | (p > 3e7 * (1 + 1e-9))
    ref = np.array([_reads_unsimulated(t, *q) for q in zip(p, v, b)]) | outside
    assert np.array_equal(flags, ref)
    assert flags.any() and not flags.all()


@pytest.mark.parametrize("version", [3, 4])
def test_a_press_delivering_a_node_minus_round_off_reads_no_unsimulated_node(version):
    """P = 9,999,999.999999996 Pa (a press holding 10 MPa) at beta 0.35, between the simulated 0.3 and the
    level 0.5 that only 10 MPa and above simulated: the weight on the 5 MPa row is ~1e-15, below 1e-9, and the lookup
    does not count; at 9.5 MPa it does. The strip-draw model counts the same."""
    rng = np.random.default_rng(8)
    t = random_table(rng, monotone=True, mask="staircase")
    if version == 3:
        t = make_table(t.pressure, t.velocity, t.beta, t.particle_area, simulated=t.array("simulated"), version=3)
    press = 9_999_999.999999996
    assert press < 1e7
    nodes, outside = t.read_nodes(press, 0.08, 0.35)
    assert not outside and {n[0] for n, _ in nodes} == {3}
    assert not t.interpolate_array(t.particle_area, press, 0.08, 0.35)[1]
    assert t.interpolate_array(t.particle_area, 9.5e6, 0.08, 0.35)[1]
    params = StripDrawParameters()
    area = params.tool_length * params.tool_width
    force = params.normal_force(1e7)
    while force / area > press:  # the force whose pressure is exactly that value
        force = np.nextafter(force, 0.0)
    assert force / area == press
    for f, counted in ((force, False), (9.5e6 * area, True)):
        model = StripDrawModel(params, make_friction_law(params, t), beta_field=np.full(params.n_elements + 1, 0.35))
        out = model.step(1e-3, {"normal_force": f, "grip_velocity": 0.08})
        assert (out["table_clamp_count"] > 0) == counted, (f / area, out["table_clamp_count"])


# ---- the cap of beta on the cubic pieces -----------------------------------------------------------------------


def test_the_first_crossing_is_found_on_a_piece_that_is_not_monotone():
    """A Hermite line below the level at both ends of a piece that rises above it inside: the first crossing is
    found inside the piece (where node values alone see none), within 1e-12 and from below."""
    from tribocosim.components.native.toolchain.library import core, ptr

    x = np.array([0.0, 1.0, 2.0])
    y = np.array([0.0, 0.5, 0.9])
    dl, dr = np.array([3.0, 0.0]), np.array([-3.0, 0.0])  # piece 0 bulges to ~1.06 between two values below 1
    at = np.zeros(1)
    lib = core().lib
    found = lib.tc_table_first_crossing(3, ptr(x), ptr(y), ptr(dl), ptr(dr), 1.0, ptr(at))
    piece = CubicHermiteSpline([0.0, 1.0], [0.0, 0.5], [3.0, -3.0])
    exact = brentq(lambda s: piece(s) - 1.0, 0.0, 0.6)
    assert found == 1 and exact - 1e-12 <= at[0] <= exact and piece(at[0]) < 1.0
    assert lib.tc_table_first_crossing(3, ptr(x), ptr(y), ptr(dl), ptr(dr), 1.2, ptr(at)) == 0


@pytest.mark.parametrize("contact_area", ["mesoscale", "eq8"])
def test_the_cap_is_where_the_interpolated_share_reaches_one_over_s(contact_area):
    """Eq. 24 on a version 4 table: the cap at (P, v) is the first beta where s A_p / A_c (mesoscale) or s A_p / A_c
    of Eq. 8 reaches 1, against brentq on the interpolated values."""
    rng = np.random.default_rng(3)
    t = random_table(rng, monotone=True, mask="staircase")  # shares up to 0.9 (A_c = 1)
    params = StripDrawParameters(particle_area_scale=2.0, contact_area=contact_area)
    ap = t.particle_area
    if contact_area == "eq8":  # A_p on the scale of Eq. 8's A_c
        ap = ap * (params.kappa * t.pressure / (params.rms_slope * params.e_star))[:, None, None]
    t = make_table(t.pressure, t.velocity, t.beta, ap, simulated=t.array("simulated"))
    law = make_friction_law(params, t)
    for p, v in ((3e6, 0.08), (15e6, 0.3), (3e7, 0.5)):
        eq8 = params.kappa * p / (params.rms_slope * params.e_star)
        ac = eq8 if contact_area == "eq8" else 1.0
        share = (lambda b: 2.0 * t.interpolate_array(ap, p, v, b)[0] / ac - 1.0)
        grid = np.linspace(0, 1, 2001)
        first = np.flatnonzero(share(grid) >= 0)
        cap = law.beta_cap(p, v)
        if first.size == 0:
            assert cap == 1.0
            continue
        exact = brentq(share, grid[first[0] - 1], grid[first[0]], xtol=1e-14)
        assert exact - 1e-11 <= cap <= exact + 1e-14, (p, v, cap, exact)
