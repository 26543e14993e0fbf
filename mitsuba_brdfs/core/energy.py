"""Energy compensation of microfacet lobes: the light lost by single scattering given back.

A microfacet lobe with F = 1 reflects E(mu) <= 1 of the light arriving at mu = cos(theta):
what it misses is the light that real rough surfaces reflect after bouncing between
microfacets, which single-scattering models leave out (rough metals render too dark). Two
ways to put it back, both driven by tables of E:

- Kulla & Conty (2017) add a lobe of its own, symmetric in the two directions (reciprocal),

      f_ms = F_ms (1 - E(mu_i)) (1 - E(mu_o)) / (pi (1 - E_avg)),
      E_avg = 2 int_0^1 E(mu) mu dmu,
      F_ms = F_avg^2 E_avg / (1 - F_avg (1 - E_avg)),   F_avg = f0 + (1 - f0) / 21,

  (F_avg is the cosine-weighted average of Schlick's F; F_ms sums the light that leaves
  after 2, 3, ... bounces, each losing 1 - F_avg of it). With F = 1 the lobe reflects
  exactly 1 - E(mu_i): lobe and compensation together reflect all the light.
- Turquin (2019) scales the single-scattering lobe by 1 + f0 (1 - E(mu_v)) / E(mu_v), mu_v
  the viewer's cosine: the same total for white, cheaper (no lobe to sample), but not
  reciprocal.

The tables (``energy_tables.json`` beside this module) hold 1 - E(mu, r) on a grid of
``N_MU`` x ``N_ROUGHNESS`` nodes, mu = i / (N_MU - 1) and r = j / (N_ROUGHNESS - 1) (the
first mu node is measured at ``MU_FIRST``, just above the horizon), and 1 - E_avg(r), for
each D x G of ``cook_torrance`` (key ``"distribution/geometry"``) and for
``torrance_sparrow``, whose exponent p enters as r = sqrt(2 / (p + 2)) (p = 2 / r^2 - 2:
the ``blinn`` roughness). They are measured with the plugins' own ``sample()`` with F = 1
(``validate.energy_tables``; ``scripts/energy_tables.py`` writes the file). Storing 1 - E
keeps its precision where E is close to 1 (smooth lobes). The grid is as large as the ones
other renderers ship for Kulla & Conty (Intel OSPRay's GGX table: 32 x 32 in (cos theta,
roughness), and a 1D average); its interpolation error stays below 2e-3 in E from 0 to 80
degrees and roughness 0.1 to 1 (measured against a 129 x 37 grid), its sampling error
below 5e-4 (1024 x 1024 points per node against 2048 x 2048). 1 - E_avg is the exact integral
of the table's own piecewise-linear 1 - E over mu, so the lobe integrates to 1 - E(mu_i)
of the table exactly and the furnace error is the table's error in E alone.

Lookup (``EnergyTable``): bilinear interpolation written in Dr.Jit, coordinates clamped to
the grid: the cell of (mu, r), its four corners gathered at once (they are stored side by
side), weights from the position in the cell. It is software interpolation on every
backend, as ``dr.Texture`` with ``use_accel=False`` would be (CUDA's texture units
interpolate with 8-bit weights: E in steps of 1/256 of a cell), and the same code on the
CPU and the GPU. Derivatives: the cell index is piecewise constant and the weights are
linear in mu and r, so automatic differentiation gives d E / d r as the slope of the cell
(the derivative of the interpolant, what a finite difference inside a cell measures:
tested, ``tests/test_energy_compensation.py``), and gradients with respect to the
roughness (or the exponent) flow through the tables; at a node the slope of the cell
above is taken. The arrays are built once per variant and table from the file read once
per process, and shared by every plugin; a plugin holds its table as an attribute (a Dr.Jit
structure, which frozen functions see as an input).

References: C. Kulla, A. Conty, "Revisiting Physically Based Shading at Imageworks",
SIGGRAPH 2017 course "Physically Based Shading in Theory and Practice"; E. Turquin,
"Practical multiple scattering compensation for microfacet models", Industrial Light &
Magic technical report, 2019.
"""
import json
import os

import drjit as dr
import mitsuba as mi

from .frame import cos_theta

__all__ = ["COMPENSATIONS", "TABLES_FILE", "N_MU", "N_ROUGHNESS", "MU_FIRST", "table_keys",
           "table_data", "mu_nodes", "roughness_nodes", "exponent_of_roughness",
           "roughness_of_exponent", "one_minus_average", "EnergyTable", "average_fresnel",
           "multiple_scattering_fresnel", "kulla_conty_f", "turquin_scale"]

#: the values of the ``energy_compensation`` parameter
COMPENSATIONS = ("none", "kulla_conty", "turquin")

#: the tables shipped with the package
TABLES_FILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "energy_tables.json")

#: nodes of the tables along mu and along the roughness
N_MU = 32
N_ROUGHNESS = 32
#: the cosine at which the first mu node (mu = 0, the horizon) is measured
MU_FIRST = 1e-3

#: E is floored here where Turquin divides by it (E >= 0.3 in every table)
_MIN_E = 1e-3
#: 1 - E_avg is floored here where Kulla-Conty divide by it (a mirror: 1 - E_avg -> 0, and
#: 1 - E with it, so the lobe vanishes)
_MIN_LOSS = 1e-7

_DATA = None
_CELLS = {}


def table_keys():
    """The tables' keys: ``"distribution/geometry"`` of ``cook_torrance``, then
    ``"torrance_sparrow"``."""
    from .microfacet import DISTRIBUTIONS, GEOMETRIES
    return tuple(f"{d}/{g}" for d in DISTRIBUTIONS for g in GEOMETRIES) + ("torrance_sparrow",)


def mu_nodes(n=N_MU):
    """The cosines at which E is measured: i / (n - 1), the first one raised to MU_FIRST."""
    return [max(i / (n - 1), MU_FIRST) for i in range(n)]


def roughness_nodes(n=N_ROUGHNESS):
    """The table's roughness nodes j / (n - 1)."""
    return [j / (n - 1) for j in range(n)]


def exponent_of_roughness(r, largest=1e6):
    """The Blinn exponent p = 2 / r^2 - 2 of a table roughness (``largest`` at r = 0)."""
    return largest if r <= 0 else min(2 / (r * r) - 2, largest)


def roughness_of_exponent(p):
    """r = sqrt(2 / (p + 2)): where ``torrance_sparrow``'s exponent enters its table."""
    return dr.sqrt(2 / (p + 2))


def one_minus_average(loss, mus=None):
    """1 - E_avg = 2 int_0^1 (1 - E(mu)) mu dmu of the piecewise-linear function through
    the nodes (``loss`` = 1 - E at the nodes ``mus``, default the table's, with the first
    node at mu = 0 as the lookup places it), integrated exactly."""
    mus = [i / (len(loss) - 1) for i in range(len(loss))] if mus is None else mus
    total = 0.0
    for a, b, ga, gb in zip(mus, mus[1:], loss, loss[1:]):
        total += (b - a) / 6 * (ga * (2 * a + b) + gb * (a + 2 * b))
    return 2 * total


def table_data():
    """The shipped tables (read once): the JSON of ``TABLES_FILE``."""
    global _DATA
    if _DATA is None:
        with open(TABLES_FILE) as f:
            _DATA = json.load(f)
    return _DATA


def _cells(key):
    """The table ``key`` as Dr.Jit arrays in the active variant (built once per variant):
    each cell's four corners of 1 - E, (j, i), (j, i + 1), (j + 1, i), (j + 1, i + 1), side
    by side (cell (j, i) at 4 ((N_MU - 1) j + i)), and 1 - E_avg at the roughness nodes."""
    tkey = (mi.variant(), key)
    if tkey not in _CELLS:
        t = table_data()["tables"][key]
        loss, avg = t["one_minus_e"], t["one_minus_e_avg"]
        cells = [v for j in range(len(loss) - 1) for i in range(len(loss[0]) - 1)
                 for v in (loss[j][i], loss[j][i + 1], loss[j + 1][i], loss[j + 1][i + 1])]
        flat = type(mi.TensorXf().array)  # a 1D array of floats in every variant
        _CELLS[tkey] = (flat(cells), flat(avg), len(loss), len(loss[0]))
    return _CELLS[tkey]


def _cell(x, n):
    """(index, fraction) of x in [0, 1] on the grid of n nodes j / (n - 1)."""
    t = dr.clip(x, 0, 1) * (n - 1)
    i = dr.minimum(mi.UInt32(t), n - 2)  # t >= 0: the conversion is floor
    return i, t - mi.Float(i)


def _gather(source, index, n=1):
    """The n adjacent values source[index * n + k], k < n (a packet gather on the JIT
    backends; in scalar variants the array's elements)."""
    if not dr.is_jit_v(mi.Float):
        return tuple(source[int(index) * n + k] for k in range(n))
    if n == 1:
        return (dr.gather(mi.Float, source, index),)
    return tuple(dr.gather(mi.Vector4f if n == 4 else mi.Vector2f, source, index))


class EnergyTable:
    """1 - E(mu, r) and 1 - E_avg(r) of one lobe, interpolated bilinearly between nodes.

    ``lookup`` gathers the four corners of the cell of (mu, r) at once (four adjacent
    floats: one packet gather on the JIT backends) and interpolates them in Dr.Jit, so the
    lookup is the same code on every backend and differentiable in mu and r (the weights
    are). Where the roughness is one number for the whole surface, ``fix_roughness``
    interpolates the table at it once (per scene, when the parameter changes), and
    ``lookup_row`` then interpolates that row in mu alone: the same bilinear interpolant,
    with half the data gathered and E_avg a kernel parameter (the lookups cost about a
    tenth of a render's time otherwise).
    """

    #: a Dr.Jit structure: frozen functions find the tables among a plugin's attributes (a
    #: plain object's fields are not searched, and arrays they miss fail to record)
    DRJIT_STRUCT = {"cells": object, "averages": object, "row": object, "row_average": object}

    def __init__(self, key):
        self.key = key
        self.cells, self.averages, self._n_r, self._n_mu = _cells(key)
        self.fix_roughness(0.0)

    def fix_roughness(self, r):
        """Interpolate the table at the roughness ``r`` (a number) for ``lookup_row``."""
        t = table_data()["tables"][self.key]
        loss, avg = t["one_minus_e"], t["one_minus_e_avg"]
        y = min(max(float(r), 0.0), 1.0) * (self._n_r - 1)
        j = min(int(y), self._n_r - 2)
        fy = y - j
        self.row = type(mi.TensorXf().array)(
            [(1 - fy) * a + fy * b for a, b in zip(loss[j], loss[j + 1])])
        self.row_average = dr.opaque(mi.Float, max((1 - fy) * avg[j] + fy * avg[j + 1], 0.0))

    def lookup(self, w, r, average=True):
        """(1 - E(cos theta_w, r), 1 - E_avg(r)) for a direction ``w`` (local frame);
        without ``average``, 1 - E alone."""
        i, fx = _cell(cos_theta(w), self._n_mu)
        j, fy = _cell(r, self._n_r)
        c = _gather(self.cells, j * (self._n_mu - 1) + i, 4)
        loss = dr.maximum(dr.lerp(dr.lerp(c[0], c[1], fx), dr.lerp(c[2], c[3], fx), fy), 0)
        if not average:
            return loss
        a0, a1 = (_gather(self.averages, j + k)[0] for k in (0, 1))
        return loss, dr.maximum(dr.lerp(a0, a1, fy), 0)

    def lookup_row(self, w, average=True):
        """``lookup`` at the roughness of the last ``fix_roughness``."""
        i, fx = _cell(cos_theta(w), self._n_mu)
        loss = dr.maximum(dr.lerp(*(_gather(self.row, i + k)[0] for k in (0, 1)), fx), 0)
        return (loss, self.row_average) if average else loss


def average_fresnel(f0):
    """F_avg = 2 int_0^1 F(mu) mu dmu of Schlick's F: f0 + (1 - f0) / 21."""
    return f0 + (1 - f0) * (1 / 21)


def multiple_scattering_fresnel(f0, loss_avg):
    """Kulla & Conty's F_ms = F_avg^2 E_avg / (1 - F_avg (1 - E_avg)) (colour of f0)."""
    f_avg = average_fresnel(f0)
    return f_avg * f_avg * (1 - loss_avg) / (1 - f_avg * loss_avg)


def kulla_conty_f(loss_i, loss_o, loss_avg, w_o):
    """The white multiple-scattering lobe (1 - E_i)(1 - E_o) / (pi (1 - E_avg)) times
    cos(theta_o) (as ``eval`` returns it); reflects 1 - E_i of the light."""
    denom = dr.maximum(loss_avg, _MIN_LOSS)
    return loss_i * loss_o / (dr.pi * denom) * dr.maximum(cos_theta(w_o), 0)


def turquin_scale(f0, loss_v):
    """Turquin's factor 1 + f0 (1 - E) / E of the single-scattering lobe (E at the viewer)."""
    return 1 + f0 * (loss_v / dr.maximum(1 - loss_v, _MIN_E))
