"""Contact clusters and surface summits on periodic grids (paper Sec. 6.3, Fig. 13-14, App. E-F).

- A *contact cluster* is a connected set of contact pixels (traction > 0); connectivity is
  4-neighbour by default (pixels touching only at a corner are separate clusters), 8-neighbour on
  request. With ``periodic=True`` the grid is a torus: pixels on opposite edges are neighbours,
  so a cluster cut by the boundary is counted once. Labelling is the two-pass method of
  Rosenfeld & Pfaltz, J. ACM 13 (1966) 471, doi:10.1145/321356.321357 (scipy.ndimage.label),
  followed by a union of labels that touch across the periodic edges.
- N_c: number of clusters; areas: pixel count times dx^2.
- d_c (Fig. 13): for each cluster, the minimum distance from its border to the border of any other
  cluster, measured between pixel centres (with the minimum-image convention when periodic);
  the mean over clusters is ``mean_cluster_distance``. Two clusters separated by one empty pixel
  have d = 2 dx; clusters touching at a corner (4-connectivity) have d = sqrt(2) dx. The closest
  pixel of a set to any outside point is a border pixel (a pixel with a 4-neighbour outside the
  set), so only border pixels enter the nearest-neighbour search (scipy cKDTree, periodic
  ``boxsize``). For N_c point-like clusters scattered uniformly (a Poisson process, App. E) the
  mean nearest-neighbour distance is L / (2 sqrt(N_c)) (Clark & Evans, Ecology 35 (1954) 445,
  doi:10.2307/1931034). The integral of Eq. 41 gives this value; the paper's Eq. 42-43 print
  L / sqrt(pi N_c), 13 % larger, which does not change the d_c ~ 1 / sqrt(p) scaling it is used
  for. Fig. 14 normalises d_c by dbar = L / sqrt(N_s).
- N_s (Fig. 14): number of summits, strict local maxima over the 8 neighbours (periodic). For a
  gap g the summits of the composite surface are the maxima of -g.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

from tribocosim.errors import ParameterError, check_range

from .surfaces import validate_height_map

_STRUCTURE = {4: ndimage.generate_binary_structure(2, 1),
              8: ndimage.generate_binary_structure(2, 2)}


def _check_connectivity(connectivity: int) -> None:
    if connectivity not in _STRUCTURE:
        raise ParameterError(f"connectivity = {connectivity!r} is not allowed; allowed: 4, 8")


def contact_clusters(mask, periodic: bool = True, connectivity: int = 4) -> tuple[np.ndarray, int]:
    """Label the connected clusters of a boolean contact map.

    Parameters
    ----------
    mask : array_like of bool, shape (n, n)
        True where in contact.
    periodic : bool
        Treat the grid as periodic (clusters touching across the edges are merged).
    connectivity : {4, 8}
        Neighbourhood of a pixel.

    Returns
    -------
    labels : ndarray of int, shape (n, n)
        0 outside contact, 1..n_clusters inside (consecutive).
    n_clusters : int
    """
    m = np.asarray(mask)
    if m.ndim != 2 or m.shape[0] != m.shape[1]:
        raise ParameterError(f"mask has shape {m.shape}; a square (n, n) array is required")
    _check_connectivity(connectivity)
    m = m.astype(bool)
    labels, count = ndimage.label(m, structure=_STRUCTURE[connectivity])
    if not periodic or count == 0:
        return labels, int(count)
    parent = np.arange(count + 1)

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    n = m.shape[0]
    shifts = [0] if connectivity == 4 else [-1, 0, 1]
    pairs = []
    for s in shifts:  # rows 0 / n-1 are neighbours, and columns 0 / n-1
        pairs.append((labels[0, :], np.roll(labels[-1, :], s)))
        pairs.append((labels[:, 0], np.roll(labels[:, -1], s)))
    for a, b in pairs:
        both = (a > 0) & (b > 0)
        for x, y in zip(a[both], b[both]):
            rx, ry = find(x), find(y)
            if rx != ry:
                parent[max(rx, ry)] = min(rx, ry)
    roots = np.array([find(i) for i in range(count + 1)])
    uniq, new = np.unique(roots, return_inverse=True)  # root 0 (background) maps to 0
    return new[labels].reshape(n, n), int(uniq.size - 1)


def cluster_statistics(field, size: float, periodic: bool = True, connectivity: int = 4) -> dict:
    """Number, areas and mean border-to-border distance of the contact clusters.

    Parameters
    ----------
    field : array_like, shape (n, n)
        Traction map (contact where > 0) or boolean contact mask.
    size : float
        Side length L of the grid [m].
    periodic : bool
        Periodic grid (minimum-image distances, clusters merged across the edges).
    connectivity : {4, 8}
        Neighbourhood of a pixel.

    Returns
    -------
    dict
        ``n_clusters`` (int), ``areas`` (ndarray [m^2], by label), ``mean_cluster_distance``
        (float [m]; NaN with fewer than two clusters), ``min_distances`` (ndarray [m], per
        cluster).
    """
    a = np.asarray(field)
    if a.dtype != bool:
        a = validate_height_map(a, "field") > 0.0
    size = check_range("size", size, 0.0, low_inclusive=False, unit="m")
    labels, count = contact_clusters(a, periodic=periodic, connectivity=connectivity)
    n = labels.shape[0]
    dx = size / n
    areas = np.bincount(labels.ravel(), minlength=count + 1)[1:] * dx * dx
    dmin = _min_border_distances(labels, count, periodic) * dx
    mean = float(np.mean(dmin)) if count >= 2 else float("nan")
    return {"n_clusters": count, "areas": areas, "mean_cluster_distance": mean,
            "min_distances": dmin}


def _min_border_distances(labels: np.ndarray, count: int, periodic: bool) -> np.ndarray:
    """Per cluster, the distance (pixels) to the nearest pixel of another cluster."""
    if count < 2:
        return np.full(count, np.nan)
    n = labels.shape[0]
    inside = labels > 0
    border = np.zeros_like(inside)
    padded = labels if periodic else np.pad(labels, 1)
    for axis in (0, 1):
        for s in (1, -1):
            nb = np.roll(padded, s, axis=axis)
            if not periodic:
                nb = nb[1:-1, 1:-1]
            border |= inside & (nb != labels)
    pts = np.argwhere(border).astype(float)
    lab = labels[border]
    tree = cKDTree(pts, boxsize=float(n) if periodic else None)
    best = np.full(len(pts), np.inf)
    todo = np.arange(len(pts))
    k = 8
    while todo.size:  # widen the search until a neighbour of another cluster is found
        kk = min(k, len(pts))
        dist, nbr = tree.query(pts[todo], k=kk)
        other = lab[nbr] != lab[todo][:, None]
        hit = other.any(axis=1)
        first = np.argmax(other, axis=1)
        best[todo[hit]] = dist[hit, first[hit]]
        todo = todo[~hit]
        if kk == len(pts):
            break
        k *= 4
    out = np.full(count, np.inf)
    np.minimum.at(out, lab - 1, best)
    return out


def count_summits(h, periodic: bool = True) -> int:
    """Number of strict local maxima of ``h`` over the 8 neighbours (periodic by default).

    Parameters
    ----------
    h : array_like, shape (n, n)
        Heights (pass ``-gap`` for the summits of a gap profile).
    periodic : bool
        Wrap around the edges; otherwise edge pixels are compared with their in-grid neighbours
        only.
    """
    h = validate_height_map(h, "h")
    pad = np.pad(h, 1, mode="wrap" if periodic else "constant",
                 **({} if periodic else {"constant_values": -np.inf}))
    n = h.shape[0]
    peak = np.ones_like(h, dtype=bool)
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            if di or dj:
                peak &= h > pad[1 + di:1 + di + n, 1 + dj:1 + dj + n]
    return int(np.count_nonzero(peak))
