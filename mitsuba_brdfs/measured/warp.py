"""The parameterization of Dupuy & Jakob's RGL files, in NumPy (float64).

Mitsuba's ``measured`` plugin (``src/bsdfs/measured.cpp``) maps directions to the unit
square: theta -> u = sqrt(2 theta / pi) (finer near the normal), phi -> (phi + pi) / 2pi.
Its VNDF and luminance tables are warped by ``Marginal2D`` (``include/mitsuba/core/
distr_2d.h``, ``Continuous = true``): a density bilinear on a grid over [0, 1]^2, sampled by
inverting its marginal (rows, y) and then conditional (columns, x) integrals, each
piecewise quadratic. ``Marginal2D`` here does the same arithmetic on one slice (one
incidence), in float64: the RGL tables hold their values on a grid of the warp's *input*
square, so that the table's nodes are measured directions only through this warp.
``tests/test_measured.py`` checks it against Mitsuba's own ``MarginalContinuous2D2``.
"""
import numpy as np

__all__ = ["node_grid", "theta2u", "u2theta", "phi2u", "u2phi", "spherical", "elevation",
           "Marginal2D", "bilinear"]


def theta2u(theta):
    return np.sqrt(np.asarray(theta) * (2 / np.pi))


def u2theta(u):
    return np.square(u) * (np.pi / 2)


def phi2u(phi):
    return (np.asarray(phi) + np.pi) / (2 * np.pi)


def u2phi(u):
    return (2 * np.asarray(u) - 1) * np.pi


def spherical(theta, phi):
    """Unit vectors (n, 3) of polar angles theta and azimuths phi."""
    theta, phi = np.broadcast_arrays(np.asarray(theta, float), np.asarray(phi, float))
    s = np.sin(theta)
    return np.stack([s * np.cos(phi), s * np.sin(phi), np.cos(theta)], -1)


def elevation(d):
    """The polar angle of unit vectors (n, 3), accurate near the normal (as measured.cpp)."""
    d = np.asarray(d, float)
    dist = np.sqrt(d[..., 0] ** 2 + d[..., 1] ** 2 + (d[..., 2] - 1) ** 2)
    return 2 * np.arcsin(np.clip(0.5 * dist, -1, 1))


def bilinear(table, pos):
    """Bilinear interpolation of ``table`` (h, w: y, x) at ``pos`` (n, 2) in [0, 1]^2, the
    grid's nodes at i / (w - 1), j / (h - 1) (``Marginal2D::eval`` without normalization)."""
    table = np.asarray(table, float)
    h, w = table.shape
    p = np.clip(np.asarray(pos, float), 0, 1) * [w - 1, h - 1]
    i = np.minimum(p.astype(int), [w - 2, h - 2])
    t = p - i
    x, y = i[:, 0], i[:, 1]
    v00, v10 = table[y, x], table[y, x + 1]
    v01, v11 = table[y + 1, x], table[y + 1, x + 1]
    return ((1 - t[:, 0]) * (1 - t[:, 1]) * v00 + t[:, 0] * (1 - t[:, 1]) * v10
            + (1 - t[:, 0]) * t[:, 1] * v01 + t[:, 0] * t[:, 1] * v11)


def _segment(s, inv_width, v0, v1):
    """``Marginal2D::sample_segment``: the fraction t of a cell where the integral of the
    density lerp(v0, v1, t) reaches s."""
    non_const = np.abs(v0 - v1) > 1e-4 * (v0 + v1)
    divisor = np.where(non_const, v0 - v1, v0 + v1)
    s = s * 2 * inv_width
    with np.errstate(invalid="ignore"):
        s = np.where(non_const, v0 - np.sqrt(np.maximum(v0 * v0 + s * (v1 - v0), 0)), s)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(divisor != 0, s / np.where(divisor != 0, divisor, 1), s)


class Marginal2D:
    """One slice of Mitsuba's continuous ``Marginal2D``: a density bilinear on the grid of
    ``data`` (h, w: rows y, columns x), normalized to integrate to 1 over [0, 1]^2."""

    def __init__(self, data):
        d = np.asarray(data, float)
        self.h, self.w = d.shape
        sx, sy = 0.5 / (self.w - 1), 0.5 / (self.h - 1)
        cond = np.cumsum(sx * (d[:, :-1] + d[:, 1:]), axis=1)          # (h, w - 1)
        rows = cond[:, -1]
        marg = np.cumsum(sy * (rows[:-1] + rows[1:]))                     # (h - 1,)
        norm = 1 / marg[-1] if marg[-1] > 0 else 1.0
        self.data, self.cond, self.marg = d * norm, cond * norm, marg * norm
        self.total = marg[-1]

    def sample(self, u):
        """(points (n, 2) in [0, 1]^2, their density) for uniform samples u (n, 2)."""
        eps = np.finfo(np.float32).eps / 2
        u = np.clip(np.asarray(u, float), eps, 1 - eps)
        sx, sy = u[:, 0].copy(), u[:, 1].copy()
        n_marg = self.h - 1
        row = np.minimum(np.searchsorted(self.marg, sy, side="left"), n_marg - 1)
        sy -= np.where(row > 0, self.marg[np.maximum(row - 1, 0)], 0)
        r0, r1 = self.cond[row, -1], self.cond[row + 1, -1]
        ty = _segment(sy, self.h - 1, r0, r1)
        sx *= r0 + (r1 - r0) * ty
        # the conditional integral of the row, interpolated at ty: the first column where
        # it reaches sx, by bisection (it increases along the row)
        cdf = lambda j: self.cond[row, j] + (self.cond[row + 1, j] - self.cond[row, j]) * ty
        lo, hi = np.zeros(len(sx), int), np.full(len(sx), self.w - 1)
        for _ in range(int(np.ceil(np.log2(self.w))) + 1):
            mid = (lo + hi) // 2
            below = cdf(np.minimum(mid, self.w - 2)) < sx
            lo, hi = np.where((lo < hi) & below, mid + 1, lo), np.where((lo < hi) & ~below,
                                                                       mid, hi)
        col = np.minimum(lo, self.w - 2)
        sx -= np.where(col > 0, cdf(np.maximum(col - 1, 0)), 0)
        d = self.data
        c0 = d[row, col] + (d[row + 1, col] - d[row, col]) * ty
        c1 = d[row, col + 1] + (d[row + 1, col + 1] - d[row, col + 1]) * ty
        tx = _segment(sx, self.w - 1, c0, c1)
        points = np.stack([(col + tx) / (self.w - 1), (row + ty) / (self.h - 1)], -1)
        return points, c0 + (c1 - c0) * tx

    def eval(self, pos):
        """The (normalized) density at points pos (n, 2)."""
        return bilinear(self.data, pos)


def node_grid(n):
    """The n x n nodes of the adapted grid as points (n * n, 2) of the unit square, in the
    tables' order (rows y, then columns x)."""
    g = np.linspace(0, 1, n)
    x, y = np.meshgrid(g, g)
    return np.stack([x.ravel(), y.ravel()], -1)
