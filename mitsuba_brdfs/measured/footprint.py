"""The values of an RGL file's adapted grid, so that ``measured``'s albedo is the source's.

Mitsuba's ``measured`` interpolates the grid's values bilinearly between the nodes, so the
directional albedo it renders is the integral of that interpolant (times rho below), a
trapezoidal rule on the nodes. Where the source is smooth over the grid the nodes hold its
eval (times 4 sigma / D, the format's factor) at their directions, and the rule is
accurate. Where it is not, the rule is not: at grazing incidence a lobe that is not
microfacet-shaped (Ashikhmin-Shirley's: 1 / (h . k) over the VNDF's density), or a sharp
lobe over a diffuse base (``roughplastic``, whose NDF the grid follows is the diffuse
part's), varies within a cell by factors of 10-1000; a file of point values at the nodes
then reflected 2.6 times its source's light at 88 deg for ``ashikhmin_shirley`` (and its
sample weights, which ``check`` averages, the same).

``grid_values``: the nodes' values at the nodes and at the cells' centres; a cell whose
centre leaves the mean of its corners by more than ``REFINE_TOL`` of the incidence's
albedo is integrated on 8 x 8 to 32 x 32 sub-cells, the further off the finer
(``REFINE_STEPS``, ``cell_integrals``), and each
node next to one holds the source's average over its footprint, its hat function times
rho (``footprint_average``): rho is the solid angle that a unit area of the grid's square
stands for relative to what the format's factor assumes (the VNDF table interpolated
bilinearly is not the analytic VNDF), 0 where the outgoing direction is below the horizon
(where ``measured`` returns 0). Then sum over nodes of value x (integral of hat x rho),
which is what ``measured`` integrates, is the source's integral over the footprints: the
albedo at each incidence is the source's, whatever the lobe does inside a cell. The other
nodes keep the source's eval exactly.

``Warp`` is one incidence's map from the square to outgoing directions, as ``measured``
warps it (``warp.Marginal2D`` on the VNDF table).
"""
import numpy as np

from . import warp
from .warp import node_grid

__all__ = ["REFINE_TOL", "REFINE", "REFINE_STEPS", "Warp", "grid_values", "cell_integrals",
           "footprint_average", "hats"]

#: a cell of the adapted grid whose centre's value leaves the mean of its corners' by more
#: than this fraction of the incidence's albedo is integrated finely (``grid_values``)
REFINE_TOL = 0.1
#: sub-cells per side of such a cell (the midpoint rule); ``REFINE_STEPS`` where its
#: centre is 1, 10, 100 times further off than that (``grid_values``)
REFINE = 8
REFINE_STEPS = (8, 16, 32)


class Warp:
    """One incidence's map from the adapted grid's square to outgoing directions, as
    ``measured`` warps it (the VNDF's ``Marginal2D``, then wo = reflect(wi, m))."""

    def __init__(self, vndf, ndf, wi, sigma, offset):
        self.marginal = warp.Marginal2D(vndf)
        self.ndf, self.wi, self.sigma, self.offset = ndf, wi, sigma, offset

    def __call__(self, points):
        """(wo (n, 3), the stored value's factor 4 sigma / D(m), rho: the solid angle of
        wo per unit area of the square over 4 sigma / D, so that eval dwo = value rho ds;
        both 0 where wo is below the horizon, where measured returns 0) of points (n, 2)
        of the square."""
        u_m, density = self.marginal.sample(points)
        theta_m = warp.u2theta(u_m[:, 0])
        m = warp.spherical(theta_m, warp.u2phi(u_m[:, 1]) + self.offset)
        cos = m @ self.wi
        wo = 2 * cos[:, None] * m - self.wi
        d = warp.bilinear(self.ndf, u_m)
        scale = np.where(wo[:, 2] > 0, 4 * self.sigma / d, 0.0)
        jacobian = 2 * np.pi ** 2 * u_m[:, 0] * np.sin(theta_m)
        with np.errstate(divide="ignore", invalid="ignore"):
            rho = np.where((density > 0) & (scale > 0), d * jacobian * np.maximum(cos, 0)
                           / (self.sigma * density), 0.0)
        return wo, scale, rho


def _values_at(evaluate, warps, points, channels):
    """The stored quantity, eval * 4 sigma / D, at ``points`` {slice: (n, 2)} of each
    slice's square (0 where wo is below the horizon), by one call of ``evaluate``: ({slice:
    (n, channels)}, {slice: rho (n,)} (``Warp``), the negative evaluations, the
    evaluations)."""
    batches, wis, wos, rhos = {}, [], [], {}
    for key, p in points.items():
        wo, scale, rhos[key] = warps[key](p)
        up = np.nonzero(scale > 0)[0]
        batches[key] = (up, scale[up], len(p))
        wis.append(np.broadcast_to(warps[key].wi, (len(up), 3)))
        wos.append(wo[up])
    count = sum(len(w) for w in wos)
    e = np.zeros((0, channels))
    if count:
        e = np.asarray(evaluate(np.concatenate(wis), np.concatenate(wos)), float)
        e = e.reshape(count, -1)
    negative = int((e < 0).sum())
    e = np.nan_to_num(e, nan=0.0, posinf=0.0, neginf=0.0)
    out, start = {}, 0
    for key, (up, scale, n) in batches.items():
        v = np.zeros((n, channels))
        v[up] = e[start:start + len(up)] * scale[:, None]
        start += len(up)
        out[key] = v
    return out, rhos, negative, count


def grid_values(evaluate, warps, slices, n, shape, steps=REFINE_STEPS):
    """The values table (n_phi, n_theta, channels, n, n) of the slices ((k, l) incidences,
    ``warps`` {slice: ``Warp``}) on the grid of n x n nodes: at each node the source's
    eval * 4 sigma / D, where it is smooth; where not, its average over the node's
    footprint (``footprint_average``), on ``steps`` sub-cells per side (the further from
    smooth, the more). Returns (table, negative evaluations, evaluations, nodes
    averaged)."""
    channels = shape[2]
    nodes = node_grid(n)
    mid = (np.arange(n - 1) + 0.5) / (n - 1)
    cx, cy = np.meshgrid(mid, mid)
    centres = np.stack([cx.ravel(), cy.ravel()], -1)       # cells: rows y, columns x
    v, _, negative, count = _values_at(evaluate, warps,
                                       {key: np.concatenate([nodes, centres])
                                        for key in slices}, channels)
    # the trapezoidal weights of the grid: measured's albedo is the mean of its values
    w = np.full(n, 1 / (n - 1))
    w[[0, -1]] /= 2
    cells, subs = {}, {}
    for key in slices:
        vn = v[key][:n * n].reshape(n, n, channels)
        vc = v[key][n * n:].reshape(n - 1, n - 1, channels)
        corners = (vn[:-1, :-1] + vn[:-1, 1:] + vn[1:, :-1] + vn[1:, 1:]) / 4
        scale = np.abs(np.einsum("y,x,yxc->c", w, w, vn)).max()
        ratio = np.abs(vc - corners).max(-1) / max(REFINE_TOL * scale, 1e-300)
        cells[key] = np.argwhere(ratio > 1)
        # finer where the cell is further from smooth: a lobe that the grid gives little
        # room (a sharp one near the horizon) needs 32 x 32 sub-cells
        level = np.clip(np.floor(np.log10(ratio[ratio > 1])), 0, len(steps) - 1)
        subs[key] = np.asarray(steps)[level.astype(int)]
    integrals, more = cell_integrals(evaluate, warps, cells, n, channels, subs)
    values = np.zeros(tuple(shape) + (n, n))
    averaged = 0
    for key in slices:
        vn = v[key][:n * n].reshape(n, n, channels)
        if len(cells[key]):
            vn, count_averaged = footprint_average(vn, cells[key], *integrals[key])
            averaged += count_averaged
        values[key] = np.moveaxis(vn, -1, 0)
    return values, negative, count + more, averaged


#: the four corners of a cell, (dy, dx) from its lower one, and their hat functions at
#: offsets (x, y) in cell units
_CORNERS = ((0, 0), (0, 1), (1, 0), (1, 1))


def hats(offsets):
    """The hat functions of a cell's four corners (``_CORNERS``) at ``offsets`` (..., 2):
    (x, y) in cell units; (..., 4)."""
    x, y = offsets[..., 0], offsets[..., 1]
    return np.stack([(1 - x) * (1 - y), x * (1 - y), (1 - x) * y, x * y], -1)


def cell_integrals(evaluate, warps, cells, n, channels, subs=None):
    """For each cell of ``cells`` {slice: (y, x) rows}, the integrals over the cell (of
    area 1) of the source's value times rho (``Warp``) and of rho, each against the hat
    function of its four corners (``_CORNERS``), by the midpoint rule on k x k sub-cells,
    k ``subs`` {slice: (cells,)} (by default ``REFINE``): ({slice: ((cells, 4, C),
    (cells, 4))}, evaluations)."""
    subs = subs or {key: np.full(len(c), REFINE) for key, c in cells.items()}
    out = {key: (np.zeros((len(c), 4, channels)), np.zeros((len(c), 4)))
           for key, c in cells.items() if len(c)}
    count = 0
    for k in sorted({int(x) for key in out for x in subs[key]}):
        t = (np.arange(k) + 0.5) / k
        grid = np.stack([a.ravel() for a in np.meshgrid(t, t)], -1)      # (k k, 2): x, y
        pick = {key: np.nonzero(subs[key] == k)[0] for key in out}
        points = {key: ((cells[key][i][:, None, ::-1] + grid[None]) / (n - 1)).reshape(-1, 2)
                  for key, i in pick.items() if len(i)}
        v, rho, _, more = _values_at(evaluate, warps, points, channels)
        count += more
        weights = hats(grid) / len(grid)                              # (k k, 4)
        for key in points:
            i = pick[key]
            f = v[key].reshape(len(i), len(grid), channels)
            r = rho[key].reshape(len(i), len(grid))
            out[key][0][i] = np.einsum("kq,mk,mkc->mqc", weights, r, f)
            out[key][1][i] = r @ weights
    return out, count


def footprint_average(vn, cells, iv, ir):
    """The values (n, n, C) with each node next to a refined cell replaced by the source's
    average over the node's footprint, weighted by its hat function (measured's bilinear
    interpolation) and by rho (``Warp``: the solid angle per unit area of the square,
    relative to what the value's factor assumes): over the refined cells (rows of
    ``cells``: (y, x) of their lower corner) the integrals ``iv``, ``ir``
    (``cell_integrals``), over the others the integral of their corners' bilinear
    interpolant (rho 1). Then measured's albedo, the integral of its interpolant times
    rho, is the source's there. Returns (values, the count of nodes averaged)."""
    n = vn.shape[0]
    flag = np.zeros((n - 1, n - 1), bool)
    flag[cells[:, 0], cells[:, 1]] = True
    num, den = np.zeros(vn.shape), np.zeros(vn.shape[:2])
    for corner, (dy, dx) in enumerate(_CORNERS):
        np.add.at(num, (cells[:, 0] + dy, cells[:, 1] + dx), iv[:, corner])
        np.add.at(den, (cells[:, 0] + dy, cells[:, 1] + dx), ir[:, corner])
    ya, xa = np.nonzero(den > 0)
    for dy, dx in _CORNERS:
        y, x = ya - dy, xa - dx                            # the cell's lower corner
        ok = (y >= 0) & (y < n - 1) & (x >= 0) & (x < n - 1)
        ok[ok] = ~flag[y[ok], x[ok]]
        y, x, yn, xn = y[ok], x[ok], ya[ok], xa[ok]
        # the integral of phi_node times the bilinear interpolant over the unit cell
        near = (4 * vn[yn, xn] + 2 * vn[yn, x + 1 - dx] + 2 * vn[y + 1 - dy, xn]
                + vn[y + 1 - dy, x + 1 - dx]) / 36
        np.add.at(num, (yn, xn), near)
        np.add.at(den, (yn, xn), 0.25)
    out = vn.copy()
    out[ya, xa] = num[ya, xa] / den[ya, xa, None]
    return out, len(ya)
