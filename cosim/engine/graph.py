"""The coupling graph: Gauss-Seidel order, direct-feedthrough order, algebraic loops.

Two graphs matter (Kübler & Schiehlen 2000, doi:10.1023/A:1009810318420; Busch 2016,
ZAMM 96:1061-1081, doi:10.1002/zamm.201500196):

- the *instance graph* (edge A -> B when an output of A feeds an input of B). A Gauss-Seidel
  master steps the instances in a topological order of it, so that B sees A's new outputs. A
  cycle (any two-way coupling) cannot be ordered: inside a strongly connected component the
  instances keep the scene order (or ``[master] order``) and the links that point backwards are
  extrapolated. The cycles and their extrapolated links are reported.
- the *feedthrough graph* on the links (edge j -> k when link k's source output depends
  directly on link j's target input). Its cycles are algebraic loops: at a communication point
  the linked outputs satisfy y = D y + s, where D (the loop Jacobian, D[k, j] =
  d y_k / d u_j) is measured by probing. A non-iterative master breaks a loop with a one-step
  delay, y_{n+1} = D y_n + s, which is stable only if the spectral radius rho(D) < 1; the same
  rho is the contraction factor of a fixed-point iteration on the loop. For a single loop of
  L links, rho(D)**L is the magnitude of the loop gain.
"""

from __future__ import annotations


def strongly_connected(n: int, edges: list[tuple[int, int]]) -> list[list[int]]:
    """Strongly connected components of a directed graph, in topological order.

    Parameters
    ----------
    n : int
        Number of nodes 0..n-1.
    edges : list of (int, int)
        Directed edges (from, to).

    Returns
    -------
    list of list of int
        The components; every edge between two components points from an earlier to a later
        one. Nodes inside a component are sorted.
    """
    succ: list[list[int]] = [[] for _ in range(n)]
    for a, b in edges:
        succ[a].append(b)
    index = [-1] * n
    low = [0] * n
    on_stack = [False] * n
    stack: list[int] = []
    out: list[list[int]] = []
    counter = 0
    for root in range(n):
        if index[root] >= 0:
            continue
        work = [(root, 0)]
        while work:
            v, i = work.pop()
            if i == 0:
                index[v] = low[v] = counter
                counter += 1
                stack.append(v)
                on_stack[v] = True
            recurse = False
            while i < len(succ[v]):
                w = succ[v][i]
                i += 1
                if index[w] < 0:
                    work.append((v, i))
                    work.append((w, 0))
                    recurse = True
                    break
                if on_stack[w]:
                    low[v] = min(low[v], index[w])
            if recurse:
                continue
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on_stack[w] = False
                    comp.append(w)
                    if w == v:
                        break
                out.append(sorted(comp))
            if work:
                u = work[-1][0]
                low[u] = min(low[u], low[v])
    out.reverse()
    return out


class StepOrder:
    """A Gauss-Seidel order and what it had to extrapolate.

    Attributes
    ----------
    order : tuple of int
        Instance indices in stepping order.
    backward : frozenset of int
        Links whose source is stepped after (or is) their target: extrapolated.
    cycles : tuple of tuple of int
        Instance cycles (strongly connected components with more than one instance or a
        self-link).
    """

    __slots__ = ("order", "backward", "cycles")

    def __init__(self, order: tuple[int, ...], backward: frozenset[int], cycles: tuple[tuple[int, ...], ...]) -> None:
        self.order, self.backward, self.cycles = order, backward, cycles


def gauss_seidel_order(n: int, links: list[tuple[int, int]], preferred: list[int] | None = None) -> StepOrder:
    """Stepping order from the instance graph.

    Parameters
    ----------
    n : int
        Number of instances.
    links : list of (source instance, target instance)
        One entry per link.
    preferred : list of int, optional
        An explicit order (``[master] order``); used as given. Otherwise components are ordered
        topologically and instances inside a component keep their index order.
    """
    edges = [(a, b) for a, b in links if a != b]
    comps = strongly_connected(n, edges)
    cycles = tuple(tuple(c) for c in comps if len(c) > 1 or any(a == b == c[0] for a, b in links))
    if preferred is not None:
        order = list(preferred)
    else:
        order = [i for comp in comps for i in comp]
    pos = {inst: k for k, inst in enumerate(order)}
    backward = frozenset(j for j, (a, b) in enumerate(links) if pos[a] >= pos[b])
    return StepOrder(tuple(order), backward, cycles)


class LoopReport:
    """An algebraic loop: the links in it and the contraction factor rho of its Jacobian."""

    __slots__ = ("links", "contraction")

    def __init__(self, links: tuple[int, ...], contraction: float) -> None:
        self.links, self.contraction = links, contraction

    def __repr__(self) -> str:
        return f"LoopReport(links={self.links!r}, contraction={self.contraction!r})"


def feedthrough_edges(dep) -> list[tuple[int, int]]:
    """Edges j -> k of the feedthrough graph from a boolean dependency matrix dep[k][j] (rows k: an (m, m) array or
    a list of m rows)."""
    return [(j, k) for k, row in enumerate(dep) for j, d in enumerate(row) if d]


def algebraic_loops(dep, jac) -> list[LoopReport]:
    """Algebraic loops and their contraction factors.

    Parameters
    ----------
    dep : (m, m) array or list of m rows of bool
        dep[k][j]: link k's source output depends directly on link j's target input.
    jac : (m, m) array or list of m rows of float
        The measured loop Jacobian D[k, j] = d y_k / d u_j.

    Returns
    -------
    list of LoopReport
        One per strongly connected component of the feedthrough graph that contains a cycle.
    """
    reports = []
    for comp in strongly_connected(len(dep), feedthrough_edges(dep)):
        if len(comp) == 1 and not dep[comp[0]][comp[0]]:
            continue
        import numpy as np  # a scene with an algebraic loop only

        sub = np.array([[jac[k][j] for j in comp] for k in comp], dtype=float)
        rho = float(max(abs(np.linalg.eigvals(sub)))) if sub.size else 0.0
        reports.append(LoopReport(tuple(comp), rho))
    return reports


def evaluation_order(n: int, links: list[tuple[int, int]], dep) -> list[int]:
    """Order in which to refresh instances' outputs at a communication point.

    Instances are ordered topologically along all links; inside a cycle of the instance graph,
    instance B comes after instance A when a link A -> B ends at an input that one of B's
    linked outputs depends on directly. Instances in an algebraic loop keep index order (the
    loop is then broken with a one-step delay, or solved by the iterative scheme).
    """
    feed = set()
    for j, (a, b) in enumerate(links):
        for k, (src, _dst) in enumerate(links):
            if src == b and dep[k][j] and a != b:
                feed.add((a, b))
    order: list[int] = []
    for comp in strongly_connected(n, [(a, b) for a, b in links if a != b]):
        if len(comp) == 1:
            order.extend(comp)
            continue
        local = {g: i for i, g in enumerate(comp)}
        sub = [(local[a], local[b]) for a, b in sorted(feed) if a in local and b in local]
        order.extend(comp[i] for c in strongly_connected(len(comp), sub) for i in c)
    return order
