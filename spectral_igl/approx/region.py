r"""Heat on a region around its sources, with a proved bound of what lies outside it.

The engine of :mod:`spectral_igl.local` and of ``heat_kernel``'s ``method="auto"`` at small t.
On a Metzler operator (lumped mass B, non-positive off-diagonal stiffness) write
:math:`A = B^{-1}L = \alpha(I - P)` with :math:`P \ge 0` (:mod:`.uniformization`). The
Dirichlet operator of a vertex set R is :math:`A_R = B_{RR}^{-1}L_{RR}` (the full diagonal of
L kept), :math:`A_R = \alpha(I - P_{RR})`, and since :math:`P \ge 0`,
:math:`(P^k)_{RR} \ge (P_{RR})^k` entrywise, so for a source :math:`s \in R`

.. math:: K^R_t = e^{-tA_R}B_{RR}^{-1}e_s = e^{-t\alpha}\sum_k \frac{(t\alpha)^k}{k!}
          P_{RR}^k B_{RR}^{-1}e_s \;\le\; K_t(R, s)

(any :math:`\alpha \ge \max_{j\in R} A_{jj}` serves, so the region's own rate is used). The
total heat :math:`M(t) = \sum_j B_{jj}K_t(j, s)` starts at 1; with the stored rows of L
summing to :math:`r = L\mathbf 1` (0 up to rounding), :math:`|M'| \le \rho M` with
:math:`\rho = \max_j |r_j|/B_{jj}`, so :math:`M(t) \le e^{\rho t}` and the non-negative
difference :math:`d = K_t(:, s) - K^R_t` (zero-extended) has

.. math:: \sum_j B_{jj} d_j \le m := e^{\rho t} - \sum_{j\in R} B_{jj}K^R_t(j),
          \qquad 0 \le d_j \le m / B_{jj},
          \qquad \|d\|_B^2 \le m^2/\min_j B_{jj},

the minimum over the source's component. :math:`K^R_t` is evaluated by
:func:`~.uniformization.uniformize` (a proved relative bound e of every entry) and m from the
computed values minus e, with every rounding accounted. Any region containing s serves, so a
block of sources shares one region and one block of products (:func:`dirichlet_heat`).

A region holding one poorly shaped element has a large rate :math:`\alpha`, and
uniformization takes about :math:`t\alpha` products there. Given an ``allowance``,
:func:`dirichlet_heat_blocks` evaluates such a region by the Chebyshev series of
:math:`e^{-tA_R}` instead (:func:`~.uniformization.chebyshev_blocks`, about
:math:`\sqrt{t\alpha\log(1/\varepsilon)}` products), whose error is proved in the
:math:`B_R`-norm: :math:`\|d\|_{B} \le \varepsilon\|g\|_B`, so each entry is within
:math:`\varepsilon\|g\|_B/\sqrt{B_{jj}}` and the heat kept in R within
:math:`\sqrt{\sum_R B_{jj}}\,\varepsilon\|g\|_B` (Cauchy--Schwarz) of the computed one;
the lower bound :math:`u - e \le K^R_t \le K_t` and the lost heat m are as above.

R is the set of vertices within a distance r of the sources along edges of L of length
:math:`\sqrt{(h^2_i + h^2_j)/2}`, :math:`h^2_j = 4B_{jj}/L_{jj}` (an equilateral mesh's squared
edge length; :func:`grow_region`); no bound relies on it.
"""
from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from ..accuracy import UNIT_ROUNDOFF as U, info as make_info, rounding_gamma as _gamma
from ..laplacian.units import dimension
from ..linalg.ldlt import region_keys
from .uniformization import (row_sums, abs_radius, chebyshev_blocks, chebyshev_rate, chebyshev_terms, poisson_terms, rate_matrix,
                             spectral_top, terms, uniformize, uniformize_blocks)

__all__ = ["region_heat_column", "dirichlet_heat", "dirichlet_heat_blocks", "grow_region", "grow_regions", "patches",
           "vertex_spacing", "heat_drift", "first_radius", "first_radii", "MAX_FRACTION", "BUDGET", "GROWTH",
           "FIRST_MARGIN"]

#: largest share of the source's component a region grows to before it takes the whole
#: component, and of all vertices before the column is declined (the global path's turn)
MAX_FRACTION = 0.25
#: largest cost of all the attempts of one column, in sparse products of the whole operator
#: (one Cholesky factorization of a surface mesh costs several hundred)
BUDGET = 200.0
#: growth of the radius per attempt, at least
GROWTH = 1.3
#: a column's first region is this many times :func:`first_radius`: the Gaussian tail's radius
#: along edges missed its goal by a factor 10--100 on scans (the ring distance overestimates the
#: geodesic one), and a second attempt cost twice the first
FIRST_MARGIN = 1.2


def heat_drift(lap) -> float:
    r""":math:`\rho \ge \max_j |(L\mathbf 1)_j| / B_{jj}`, cached on ``lap``.

    A proof: the computed row sums plus their rounding, :math:`\gamma_r \sum_k |L_{jk}|` with
    :math:`\sum_k|L_{jk}| \le 2L_{jj} + |r_j|` on a Metzler L. The total heat of a column grows
    by at most :math:`e^{\rho t}`.
    """
    def build():
        L = sp.csr_matrix(lap.L)
        r = np.abs(L @ np.ones(lap.n))
        width = int(np.max(np.diff(L.indptr), initial=0)) + 1
        g = _gamma(width + 2)
        bound = (r + g * (2.0 * L.diagonal() + r)) * (1.0 + 4 * U)
        return float(np.max(bound / lap.mass, initial=0.0)) * (1.0 + 4 * U)

    return lap.cache.fetch("bound", "row_sum_drift", build)


def vertex_spacing(lap) -> np.ndarray:
    """(n,) squared spacing 4 B_jj / L_jj of each vertex (an equilateral mesh's squared edge
    length), cached on ``lap``; inf where L_jj = 0."""
    def build():
        d = lap.L.diagonal()
        with np.errstate(divide="ignore"):
            return np.where(d > 0, 4.0 * lap.mass / np.where(d > 0, d, 1.0), np.inf)

    return lap.cache.fetch("bound", "vertex_spacing", build)


def _edges(L: sp.csr_matrix, rows: np.ndarray):
    """(index into ``rows`` of each edge, column of each edge, its position in L.data) of the
    given rows of L, row by row in L's order."""
    starts, stops = L.indptr[rows], L.indptr[rows + 1]
    counts = stops - starts
    pos = np.repeat(stops - np.cumsum(counts), counts) + np.arange(int(counts.sum()))
    return np.repeat(np.arange(rows.size), counts), L.indices[pos], pos


def _neighbours(L: sp.csr_matrix, rows: np.ndarray):
    """(row of each edge, column of each edge) of the given rows of L."""
    owner, cols, _ = _edges(L, rows)
    return rows[owner], cols


def grow_region(L, h2, sources, radius: float, limit: int | None = None):
    """Vertices within ``radius`` of ``sources`` along edges of L.

    Edge (i, j) has length sqrt((h2_i + h2_j) / 2); the region is found ring by ring (a
    vertex's distance through the ring before it: an over-estimate, which only makes the region
    smaller; no bound relies on it).

    Parameters
    ----------
    L : (n, n) scipy.sparse.csr_matrix
    h2 : (n,) float
        Squared spacing of each vertex (:func:`vertex_spacing`).
    sources : int or (m,) int
    radius : float
    limit : int, optional
        Stop once the region holds more than this many vertices.

    Returns
    -------
    R : (k,) int
        Sorted vertices of the region (``None`` when it passed ``limit``).
    nearest_out : float
        The smallest distance of a vertex left out (the radius that adds at least one vertex).
    """
    dist = np.full(L.shape[0], np.inf)
    frontier = np.unique(np.atleast_1d(np.asarray(sources, dtype=np.int64)))
    dist[frontier] = 0.0
    count, nearest_out, rings = frontier.size, np.inf, [frontier]
    while frontier.size:
        i, j = _neighbours(L, frontier)
        new = np.isinf(dist[j])
        i, j = i[new], j[new]
        d = dist[i] + np.sqrt(0.5 * (h2[i] + h2[j]))
        order = np.lexsort((d, j))
        j, d = j[order], d[order]
        first = np.r_[True, j[1:] != j[:-1]] if j.size else np.zeros(0, bool)
        j, d = j[first], d[first]
        inside = d <= radius
        if not inside.all():
            nearest_out = min(nearest_out, float(np.min(d[~inside])))
        frontier = j[inside]
        dist[frontier] = d[inside]
        rings.append(frontier)
        count += frontier.size
        if limit is not None and count > limit:
            return None, nearest_out
    return np.sort(np.concatenate(rings)), nearest_out


def grow_regions(L, h2, sources, offsets, radii, limits, labels):
    """:func:`grow_region` for many groups of sources at once, each with its own radius.

    Parameters
    ----------
    L : (n, n) scipy.sparse.csr_matrix
    h2 : (n,) float
        Squared spacing of each vertex (:func:`vertex_spacing`).
    sources : (m,) int
        The sources of every group, group after group.
    offsets : (g + 1,) int
        Group b holds ``sources[offsets[b]:offsets[b+1]]`` (at least one).
    radii : (g,) float
    limits : (g,) int
        A group whose region passes this many vertices takes its whole component instead.
    labels : (n,) int
        Connected component of each vertex (a group lies in one).

    Returns
    -------
    keys : (k,) int64
        Sorted ``group * n + vertex`` of every region's vertices: group after group, each
        region's vertices ascending.
    region_offsets : (g + 1,) int
        Group b's region is ``keys[region_offsets[b]:region_offsets[b+1]] % n``.
    """
    compiled = region_keys(L, h2, sources, offsets, radii, limits, labels)
    if compiled is not None:
        return compiled
    n = L.shape[0]
    count = len(offsets) - 1
    group = np.repeat(np.arange(count, dtype=np.int64), np.diff(offsets))
    seen = np.unique(group * n + np.asarray(sources, dtype=np.int64))
    front, dist = seen, np.zeros(seen.size)
    size = np.bincount(seen // n, minlength=count)
    over = size > limits
    while front.size:
        g, v = np.divmod(front, n)
        e, j, _ = _edges(L, v)
        d = dist[e] + np.sqrt(0.5 * (h2[v[e]] + h2[j]))
        k = g[e] * n + j
        at = np.minimum(np.searchsorted(seen, k), seen.size - 1)
        new = seen[at] != k
        k, d = k[new], d[new]
        order = np.lexsort((d, k))
        k, d = k[order], d[order]
        first = np.r_[True, k[1:] != k[:-1]] if k.size else np.zeros(0, bool)
        k, d = k[first], d[first]
        inside = d <= radii[k // n]
        front, dist = k[inside], d[inside]
        size += np.bincount(front // n, minlength=count)
        over |= size > limits
        keep = ~over[front // n]
        front, dist = front[keep], dist[keep]
        seen = np.sort(np.concatenate([seen, front]))
    if over.any():
        seen = seen[~over[seen // n]]
        whole = [b * n + np.flatnonzero(labels == labels[sources[offsets[b]]]) for b in np.flatnonzero(over)]
        seen = np.sort(np.concatenate([seen] + whole))
    region_offsets = np.zeros(count + 1, dtype=np.int64)
    np.cumsum(np.bincount(seen // n, minlength=count), out=region_offsets[1:])
    return seen, region_offsets


def patches(L, size: int):
    """Split the vertices into connected patches of about ``size`` vertices.

    Seeds are taken in reverse Cuthill--McKee order and each patch grows ring by ring over
    vertices not yet taken, so patches are compact and neighbouring patches are made one
    after the other.

    Parameters
    ----------
    L : (n, n) scipy.sparse.csr_matrix
    size : int

    Returns
    -------
    list of (k,) int arrays
        Every vertex in exactly one patch, each patch within one connected component.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> from spectral_igl.approx.region import patches
    >>> lap = sig.laplacian(*icosphere(3))
    >>> parts = patches(lap.L, 64)
    >>> bool(np.array_equal(np.sort(np.concatenate(parts)), np.arange(lap.n))), max(p.size for p in parts)
    (True, 64)
    """
    from scipy.sparse.csgraph import reverse_cuthill_mckee

    L = sp.csr_matrix(L)
    n = L.shape[0]
    # rings of a few dozen vertices: Python's sets and lists beat numpy's per-call cost there
    ptr, ind = L.indptr.tolist(), L.indices.tolist()
    taken = bytearray(n)
    out = []
    order = reverse_cuthill_mckee(L, symmetric_mode=True)
    dtype = np.result_type(order.dtype, L.indices.dtype)
    for seed in order.tolist():
        if taken[seed]:
            continue
        taken[seed] = 1
        members, frontier, count = [seed], [seed], 1
        while count < size and frontier:
            ring = set()
            for v in frontier:
                ring.update(ind[ptr[v]:ptr[v + 1]])
            j = [w for w in sorted(ring) if not taken[w]][:size - count]
            for w in j:
                taken[w] = 1
            members.extend(j)
            count += len(j)
            frontier = j
        out.append(np.sort(np.array(members, dtype=dtype)))
    return out


def dirichlet_heat(lap, t: float, R: np.ndarray, sources, tail: float, mass=None):
    r"""Heat columns of ``sources`` on the region R with zero values outside it, with proofs.

    Parameters
    ----------
    lap : Laplacian
        Metzler.
    t : float
        Absolute time.
    R : (k,) int
        Sorted vertices, holding every source.
    sources : (m,) int
    tail : float
        Allowed truncation of the series, relative to each column's peak :math:`1/B_{ss}`.
    mass : (n,) float, optional
        ``lap.mass``, when the caller holds it already.

    Returns
    -------
    u : (k, m) float
        :math:`K^R_t` on R (module notes), non-negative.
    e : (k, m) float
        Proved bound of each entry's error against the exact :math:`K^R_t`; so
        :math:`u - e \le K_t` entrywise.
    lost : (m,) float
        Proved bound m of the heat of each column outside R: the exact column is within
        :math:`e_j + m/B_{jj}` of u at every vertex j of the source's component.
    products : int
        Sparse products taken on R (per block).

    Notes
    -----
    Module notes: :math:`u - e \le K^R_t \le K_t` on R, and the heat kept in R, summed from
    :math:`(u - e)^+` with its rounding, bounds the heat outside from above.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> from spectral_igl.approx.region import dirichlet_heat
    >>> lap = sig.laplacian(*icosphere(3))
    >>> R = np.arange(lap.n)                      # the whole sphere: nothing leaves it
    >>> u, e, lost, k = dirichlet_heat(lap, 1e-2, R, [0, 5], 1e-14)
    >>> u.shape, bool(np.all(lost < 1e-10))
    ((642, 2), True)
    """
    sources = np.asarray(sources, dtype=np.int64).reshape(-1)
    mass = (lap.mass if mass is None else mass)[R]
    alpha, P = rate_matrix(lap.L[R][:, R], mass)
    G = np.zeros((R.size, sources.size))
    pos = np.searchsorted(R, sources)
    G[pos, np.arange(sources.size)] = 1.0 / mass[pos]
    if P is None:
        u, e, products = G, np.zeros_like(G), 0
    else:
        u, e = uniformize(P, alpha, t, G, tail)
        products = terms(t, alpha, tail)
    # 1 / B_ss is rounded by u relative, which moves the exact kernel by as much
    e = e + 2.0 * U * (u + e)
    return u, e, _lost(lap, t, mass @ np.maximum(u - e, 0.0), R.size), products


def _lost(lap, t, kept, size):
    """Proved bound of the heat outside a region of ``size`` vertices, from the computed heat
    ``kept`` in it, sum_j B_jj (u_j - e_j)^+ (its rounding relative gamma_{size+2})."""
    kept = kept * (1.0 - _gamma(np.asarray(size) + 2))
    top = math.exp(heat_drift(lap) * t) * (1.0 + 8.0 * U)
    return np.maximum(top - kept, 0.0) * (1.0 + 4.0 * U)


def dirichlet_heat_blocks(lap, t: float, keys, region_offsets, sources, offsets, tail: float, mass=None,
                          allowance=None):
    r""":func:`dirichlet_heat` for many groups of sources, each on its own region, in one series.

    The regions' Dirichlet operators are stacked into one block-diagonal operator, each block
    with its own rate (:func:`~.uniformization.uniformize_blocks`), so one sparse product per
    term serves every group: the proofs are those of :func:`dirichlet_heat`, block by block.

    Parameters
    ----------
    lap : Laplacian
        Metzler.
    t : float
        Absolute time.
    keys, region_offsets : from :func:`grow_regions`
        Group b's region, holding its sources.
    sources : (m,) int
    offsets : (g + 1,) int
        Group b's sources are ``sources[offsets[b]:offsets[b+1]]``.
    tail : float
        Allowed truncation of the series, relative to each column's peak :math:`1/B_{ss}`.
    mass : (n,) float, optional
    allowance : (g,) float, optional
        When given, a region whose Chebyshev series
        (:func:`~.uniformization.chebyshev_blocks`) is cheaper than its uniformization takes
        it, with a B-norm error of at most ``allowance[b]`` :math:`/\sqrt{\sum_R B_{jj}}` times
        the column's: the heat it proves kept in R is then within ``allowance[b]`` times the
        column's B-norm (Cauchy--Schwarz) of the computed one. Its entries' bounds are then
        absolute (``rel`` 0 but the rounding of :math:`1/B_{ss}`), not relative.

    Returns
    -------
    u : (k, w) float
        Row r of block b (the vertex ``keys[r] % n``), column c: :math:`K^R_t` of the group's
        c-th source (w the largest group; columns past a group's size are 0).
    rel, add : (g,) float and (k, w) float
        The proved bound of u's error against the exact :math:`K^R_t` is
        ``e = rel[b] * u + add`` on block b (:func:`dirichlet_heat`'s e, the rounding of
        :math:`1/B_{ss}` included).
    lost : (g, w) float
        Proved bound m of each column's heat outside its region.
    products : float
        Sparse products of the whole operator spent (entries of the regions' operators
        multiplied, over L's). Fastest with the groups in decreasing order of their regions'
        largest :math:`L_{jj}/B_{jj}`: each block then stops at its own number of terms.
    """
    n = lap.n
    mass = lap.mass if mass is None else mass
    L = sp.csr_matrix(lap.L)
    verts = keys % n
    # the regions' principal submatrices of L, stacked: edge (r, j) kept when j is in r's region
    e, j, pos = _edges(L, verts)
    # each edge's row in the stack (-1 outside the region), a region at a time through a map of
    # the vertices (random reads of n entries, not a search of all the batch's keys per edge)
    at = np.empty(j.size, dtype=np.int64)
    where = np.full(n, -1, dtype=np.int64)
    starts = np.searchsorted(e, region_offsets).tolist()
    bounds = np.asarray(region_offsets).tolist()
    for g in range(len(bounds) - 1):
        a, b = bounds[g], bounds[g + 1]
        where[verts[a:b]] = np.arange(a, b)
        at[starts[g]:starts[g + 1]] = where[j[starts[g]:starts[g + 1]]]
        where[verts[a:b]] = -1
    inside = at >= 0
    indptr = np.zeros(keys.size + 1, dtype=np.int64)
    np.cumsum(np.bincount(e[inside], minlength=keys.size), out=indptr[1:])
    stacked = sp.csr_matrix((L.data[pos[inside]], at[inside], indptr), shape=(keys.size, keys.size))
    del e, j, pos, at, inside, where
    m = mass[verts]
    counts = np.diff(offsets)
    width = int(counts.max())
    col = np.arange(sources.size) - np.repeat(offsets[:-1], counts)
    row = np.searchsorted(keys, np.repeat(np.arange(counts.size, dtype=np.int64), counts) * n + sources)
    G = np.zeros((keys.size, width))
    G[row, col] = 1.0 / mass[sources]
    rsize = np.diff(region_offsets)
    cheb = _chebyshev_choice(lap, t, stacked, m, region_offsets, tail, allowance)
    if cheb is None:
        alpha, P = rate_matrix(stacked, m, region_offsets)
        u, rel, add, work = uniformize_blocks(P, alpha, region_offsets, t, G, tail)
        bnorm = None
    else:
        u, rel, add, bnorm, work = _mixed_blocks(t, stacked, m, region_offsets, G, tail, cheb)
    del G
    # 1 / B_ss is rounded by u relative, which moves the exact kernel by as much (dirichlet_heat)
    # (and the products and sums forming e below, within 4u of e)
    rel = ((1.0 + 2.0 * U) * rel + 2.0 * U) * (1.0 + 4.0 * U)
    add = (1.0 + 2.0 * U) * add * (1.0 + 4.0 * U)
    err = np.repeat(rel, rsize)[:, None] * u + add
    low = np.maximum(u - err, 0.0)
    low *= m[:, None]
    kept = np.add.reduceat(low, region_offsets[:-1], axis=0)
    if bnorm is not None:
        kept = np.maximum(kept, _kept_bnorm(u, m, region_offsets, rel, bnorm))
    return u, rel, add, _lost(lap, t, kept, rsize[:, None]), work / L.nnz


#: a block takes the Chebyshev series when its degree is below this share of its Poisson terms
CHEBYSHEV_GAIN = 0.85


def _chebyshev_choice(lap, t, stacked, m, region_offsets, tail, allowance):
    """(is Chebyshev, rates, plans, volumes, spectral tops) of the regions of :func:`dirichlet_heat_blocks`:
    the blocks whose Chebyshev degree at their B-norm allowance (``allowance`` over the square
    root of the region's mass) is below :data:`CHEBYSHEV_GAIN` of their uniformization terms;
    None when none is."""
    if allowance is None:
        return None
    d = stacked.diagonal() / m
    least = 1.0625 * np.maximum.reduceat(d, region_offsets[:-1])
    poisson = poisson_terms(t, least, tail)
    try_ = np.flatnonzero(poisson >= 24)
    if not try_.size:
        return None
    rates = least.copy()
    # half the proved top of each region's spectrum: the series' interval, so its degree,
    # shrinks with it (spectral_top is well below 2 max L_jj / B_jj where the masses vary);
    # the row sums it reads serve abs_radius too
    sums = row_sums(stacked, m, region_offsets)
    top = spectral_top(stacked, m, region_offsets, sums=sums)
    rates[try_] = chebyshev_rate(0.5 * top[try_])
    volume = np.add.reduceat(m, region_offsets[:-1]) * (1.0 + _gamma(np.diff(region_offsets) + 2))
    eps = np.asarray(allowance, dtype=float)[try_] / np.sqrt(volume[try_])
    # each block's rho(|P|) at its rate (the rounding of the products grows with it)
    omega = abs_radius(stacked, m, region_offsets, np.where(rates > 0, rates, 1.0), sums=sums)[try_]
    degree, plans = chebyshev_terms(stacked, rates[try_], t, eps, heat_drift(lap), omega)
    use = (degree >= 0) & (degree < CHEBYSHEV_GAIN * poisson[try_])
    if not use.any():
        return None
    mask = np.zeros(least.size, dtype=bool)
    mask[try_[use]] = True
    chosen = [None] * least.size
    for b, p in zip(try_[use].tolist(), [plans[i] for i in np.flatnonzero(use)]):
        chosen[b] = p
    return mask, rates, chosen, volume, top


def _sub_blocks(M, region_offsets, blocks):
    """(rows, the block-diagonal M restricted to those blocks, their offsets)."""
    sizes = np.diff(region_offsets)[blocks]
    offs = np.r_[0, np.cumsum(sizes)]
    rows = np.repeat(region_offsets[blocks] - offs[:-1], sizes) + np.arange(offs[-1])
    owner, cols, pos = _edges(M, rows)
    # block diagonal: a row's columns lie in its block, moved as its rows are
    shift = np.repeat(offs[:-1] - region_offsets[blocks], sizes)[owner]
    indptr = np.r_[0, np.cumsum(np.bincount(owner, minlength=rows.size))]
    sub = sp.csr_matrix((M.data[pos], cols + shift, indptr), shape=(rows.size, rows.size))
    return rows, sub, offs


def _mixed_blocks(t, stacked, m, region_offsets, G, tail, cheb):
    """:func:`dirichlet_heat_blocks`' series: the chosen blocks by Chebyshev
    (:func:`~.uniformization.chebyshev_blocks`), the others by uniformization, each a proof;
    (u, rel, add, bnorm (g, w) with inf where uniformized, work)."""
    mask, rates, plans, volume, top = cheb
    if mask.all():                               # every block by Chebyshev: the stacked operator itself
        _, P = rate_matrix(stacked, m, region_offsets, alpha=rates, nonnegative=False, top=top)
        u, add, bnorm, work = chebyshev_blocks(P, rates, region_offsets, t, G, m, plans, volume)
        return u, np.zeros(mask.size), add, bnorm, work
    u, add = np.empty_like(G), np.empty_like(G)
    rel = np.zeros(mask.size)
    bnorm = np.full((mask.size, G.shape[1]), np.inf)
    work = 0
    for use in (True, False):
        blocks = np.flatnonzero(mask == use)
        if not blocks.size:
            continue
        rows, sub, offs = _sub_blocks(stacked, region_offsets, blocks)
        if use:
            _, P = rate_matrix(sub, m[rows], offs, alpha=rates[blocks], nonnegative=False, top=top[blocks])
            u[rows], add[rows], bnorm[blocks], w = chebyshev_blocks(
                P, rates[blocks], offs, t, G[rows], m[rows], [plans[b] for b in blocks], volume[blocks])
        else:
            alpha, P = rate_matrix(sub, m[rows], offs)
            u[rows], rel[blocks], add[rows], w = uniformize_blocks(P, alpha, offs, t, G[rows], tail)
        work += w
    return u, rel, add, bnorm, work


def _kept_bnorm(u, m, region_offsets, rel, bnorm):
    """A lower bound of each column's exact heat in its region from the B-norm bound of its
    error (Cauchy--Schwarz: sum_j B_jj |d_j| <= sqrt(sum_j B_jj) ||d||_B), before the rounding
    of the sum that :func:`_lost` takes off; 0 where it is not positive."""
    size = np.diff(region_offsets)
    heat = np.add.reduceat(m[:, None] * u, region_offsets[:-1], axis=0)
    root = np.sqrt(np.add.reduceat(m, region_offsets[:-1]) * (1.0 + _gamma(size + 2)))[:, None]
    # the rounding of 1 / B_ss (rel) moves the exact heat by rel of it
    low = (heat * (1.0 - rel[:, None]) - root * bnorm * (1.0 + 8.0 * U)) * (1.0 - 2.0 * U)
    return np.maximum(np.nan_to_num(low, nan=0.0, neginf=0.0), 0.0)


def _ball_measure(radius: float, d: int) -> float:
    """Area (d = 2) or volume (d = 3) of a flat ball of the given radius."""
    return math.pi * radius ** 2 if d == 2 else 4.0 / 3.0 * math.pi * radius ** 3


def first_radius(t: float, h2_source: float, goal: float) -> float:
    """The radius a region starts from: a Gaussian's tail :math:`\\sqrt{4t\\log(1/m)}` for the
    heat m allowed outside, or, where t is short against the source's own rate and heat moves by
    hops (k rings away with probability about :math:`(t\\alpha)^k/k!`), the hops a Poisson tail
    allows."""
    rate_time = 4.25 * t / h2_source
    hops = min(terms(t, 4.25 / h2_source, min(goal, 0.5)), 6) if rate_time < 0.2 else 0
    return max(float(_gaussian_radius(t, goal)), hops * math.sqrt(h2_source) if hops else 0.0)


def _gaussian_radius(t, goal):
    """sqrt(4 t log(1/goal)) (0 where goal >= 1): the radius beyond which a Gaussian's heat is goal."""
    goal = np.asarray(goal, dtype=float)
    return np.sqrt(4.0 * t * np.log(1.0 / np.minimum(goal, 1.0)))


def first_radii(t: float, h2, goal) -> np.ndarray:
    """:func:`first_radius` of many sources (their squared spacings and allowed heats), at once."""
    h2 = np.asarray(h2, dtype=float)
    goal = np.asarray(goal, dtype=float)
    radii = _gaussian_radius(t, goal)
    hop = np.flatnonzero(4.25 * t / h2 < 0.2)
    if hop.size:
        hops = np.minimum(poisson_terms(t, 4.25 / h2[hop], np.minimum(goal[hop], 0.5)), 6)
        # (an isolated vertex's spacing is inf and its rate 0: no hops, and no 0 * inf)
        radii[hop] = np.maximum(radii[hop], hops * np.sqrt(np.where(hops > 0, h2[hop], 0.0)))
    return radii


def region_heat_column(lap, t: float, source: int, tol: float, budget: float = BUDGET):
    r"""One heat column :math:`e^{-t\tilde L}B^{-1}e_s` on a region grown until its proved
    B-norm bound meets ``tol`` :math:`\cdot\|B^{-1}e_s\|_B`, or ``None`` when that would cost
    too much.

    Parameters
    ----------
    lap : Laplacian
        Metzler.
    t : float
        Absolute time.
    source : int
    tol : float
    budget : float
        Largest cost of all attempts, in sparse products of the whole operator; a region of
        more than :data:`MAX_FRACTION` of the vertices is declined too.

    Returns
    -------
    K : (n,) float or None
    info : dict
        The accuracy ``info`` (:mod:`spectral_igl.accuracy`) of the column: ``abs_error``,
        ``bound_kind`` ``"proof"``, ``method`` ``"local"``, ``bnorm_error``, ``tol``,
        ``region``, ``m_lost``, ``products``, ``solver_error``, ``cost`` (products of the whole
        operator spent); when declined only ``note`` (why) and ``cost``.

    Notes
    -----
    The region starts at :data:`FIRST_MARGIN` times :func:`first_radius` and grows by the Gaussian tail's law
    (:math:`\log(1/m)` like the squared radius) until the bound of the module notes meets
    ``tol``; each attempt's cost is predicted before it runs (the Poisson terms at the region's
    rate times its share of the stored entries of L), so a declined column costs at most
    ``budget`` products.

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> from spectral_igl.approx.region import region_heat_column
    >>> lap = sig.laplacian(*icosphere(4))
    >>> k, info = region_heat_column(lap, 1e-3, 0, 1e-8)
    >>> info["method"], info["region"] < lap.n // 4, bool(info["bnorm_error"] <= 1e-8 / lap.mass[0] ** 0.5)
    ('local', True, True)
    >>> region_heat_column(lap, 1.0, 0, 1e-8)[0] is None
    True
    """
    n, mass, L = lap.n, lap.mass, lap.L
    comp = lap.components == lap.components[source]
    size = int(np.count_nonzero(comp))
    min_mass = float(np.min(mass[comp]))
    target = tol / math.sqrt(mass[source])           # tol * ||B^-1 e_s||_B
    goal = 0.5 * target * math.sqrt(min_mass)        # heat allowed outside R
    area = float(np.sum(mass[comp]))
    # truncation of the series: at most tail / B_ss per entry, 1e-3 of the target in the B-norm
    tail = min(1e-3 * tol * math.sqrt(mass[source] / area), 1e-3)
    h2 = vertex_spacing(lap)
    plain = first_radius(t, h2[source], goal)
    limit = int(MAX_FRACTION * n)
    d = dimension(lap)
    if d in (2, 3) and _ball_measure(plain, d) > MAX_FRACTION * area and size > limit:
        # the first region would already be a flat ball of more than the share allowed: the
        # global path's turn, without growing a region ring by ring to find it out
        return None, {"note": f"the first region's radius {plain:.3g} spans more than "
                              f"{MAX_FRACTION:g} of the component's measure", "cost": 0.0}
    radius, margined = FIRST_MARGIN * plain, True
    spent = 0.0
    while True:
        R, nearest_out = grow_region(L, h2, source, radius, limit=max(int(MAX_FRACTION * size), 1))
        if margined and (R is None or R.size > limit):
            radius, margined = plain, False         # the margin alone passed the share allowed
            continue
        margined = False
        if R is None:                               # no use growing further: the whole component
            R = np.flatnonzero(comp)
        whole = R.size == size
        if R.size > limit:
            return None, {"note": f"the region would cover {R.size} of the {n} vertices (more "
                                  f"than {MAX_FRACTION:g})", "cost": spent}
        row_nnz = float(np.sum(L.indptr[R + 1] - L.indptr[R]))
        cost = terms(t, 4.25 / float(np.min(h2[R])), tail) * row_nnz / L.nnz
        if not whole and spent + cost > budget:
            return None, {"note": f"the region's {R.size} vertices would take {cost:.3g} products "
                                  f"of the whole operator (with {spent:.3g} spent, more than "
                                  f"{budget:g})", "cost": spent}
        u, e, lost, products = dirichlet_heat(lap, t, R, [source], tail, mass)
        u, e, lost = u[:, 0], e[:, 0], float(lost[0])
        spent += products * row_nnz / L.nnz
        bnorm = (lost / math.sqrt(min_mass) + math.sqrt(float(np.sum(mass[R] * e * e)))) * (1.0 + 1e-12)
        if bnorm <= target or whole:
            break
        if 0.0 < lost < 1.0 and goal < 1.0:
            grow = max(GROWTH, 1.05 * math.sqrt(math.log(1.0 / goal) / math.log(1.0 / lost)))
        else:
            grow = 2.0
        radius = max(grow * radius, nearest_out)
    K = np.zeros(n)
    K[R] = u
    err = np.zeros(n)
    err[comp] = lost / mass[comp] * (1.0 + 2.0 * U)
    err[R] += e
    solver = np.zeros(n)
    solver[R] = e
    return K, make_info(err, "proof", "local", tol=tol, bnorm_error=bnorm, region=int(R.size),
                        m_lost=lost, products=int(products), solver_error=solver, cost=spent)
