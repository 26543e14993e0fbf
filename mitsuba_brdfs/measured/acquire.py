"""A virtual measurement: any reflectance (a function eval(wi, wo)) as the tables of an RGL
file, the way Dupuy & Jakob measure a real material.

1. **NDF.** The retro-reflection r(w) = eval(w, w) = f(w, w) cos(theta) is measured on the
   NDF grid. In a microfacet model whose masking is Smith's and in which masking and
   shadowing coincide when light and viewer do, f(w, w) = F D(w) / (4 cos(theta) sigma(w))
   with sigma(w) = integral of <w, m>+ D(m) dm, so D is the eigenvector of the linear
   operator D -> r * sigma[D] (a Fredholm equation); power iteration finds it. Here the
   azimuthal integral of <w, m>+ is exact (closed form) and the polar one a trapezoidal
   rule in the grid's u = sqrt(2 theta / pi), with its Jacobian. The iteration stops when
   no value changes by more than 1e-9 of the peak (3-12 iterations on this package's
   models).
2. **sigma** on the same grid, and D scaled so that sigma(normal) = 1 (as in RGL files).
3. **The parameterization NDF** is D mixed with a uniform one (``UNIFORM_SHARE`` of the
   projected area, as a Lambertian surface's): a diffuse part of a material whose
   retro-reflection D puts all its weight into a sharp peak keeps grid nodes then.
   The file stores this mixture as ``ndf``: eval = value * D / (4 sigma) holds for any
   positive D, the NDF only decides where the grid's nodes go.
4. **Incidences** theta_i where sigma falls in equal steps from sigma(0) = 1 to
   sigma(``LAST_THETA``) (the paper's rule); for an RGL source, its own incidences and
   points halfway between them (``refine``), where its values are measured. The last one
   stays below 90 deg: at 90 deg the VNDF is zero over half of its rows, and Mitsuba's
   warp then divides 0 by 0 (the NaN that ``check`` finds in RGL files at the horizon);
   incidences beyond the last use its tables.
5. **VNDF** per incidence: 2 pi^2 u sin(theta_m) <wi, m>+ D(m) / sigma(wi) on its grid.
6. **Values** on the adapted grid: each node is warped by the VNDF (as Mitsuba's
   ``measured`` warps it: ``warp.Marginal2D`` on the float32 table) to a half vector m,
   hence to wo = reflect(wi, m); the source is evaluated there and stored as
   eval * 4 sigma(wi) / D(m), with sigma and D interpolated as Mitsuba interpolates them,
   so that ``measured`` returns the source's eval exactly at every node. Nodes whose wo is
   below the horizon hold 0. Negative values (out-of-gamut colours of a measurement) are
   set to 0 (``measured`` would return negative radiance, and negative sample weights)
   and the rest of their channel scaled so that the channel's albedo at that incidence
   stays the source's (``clip_keeping_albedo``). The luminance table (which ``measured``
   samples) is the luminance (Rec. 709 weights) of the values, or the mean over
   wavelengths.

Isotropic sources: one azimuth phi_i = 0, half vectors' azimuths relative to the
incidence's, ``ndf``/``sigma`` with two equal rows (as RGL's isotropic files).
Anisotropic ones: azimuths of incidence over the whole circle, both ends included
(``measured`` then folds nothing), half vectors' azimuths absolute, and the NDF a power
iteration on a grid of the hemisphere (``Resolution.ndf_phi`` x ``ndf_aniso``).

References: J. Dupuy, W. Jakob, "An Adaptive Parameterization for Efficient Material
Acquisition and Rendering", ACM TOG 37(6) 2018, sections 4-5; NVIDIA Falcor's
``RGLAcquisition`` follows the same steps.
"""
import dataclasses

import numpy as np

from . import footprint, warp

__all__ = ["Resolution", "UNIFORM_SHARE", "LAST_THETA", "LUMINANCE", "acquire",
           "power_iteration", "projected_area", "clip_keeping_albedo", "luminance", "refine"]

#: share of the parameterization NDF's projected area given to a uniform NDF
UNIFORM_SHARE = 0.05
#: the last incidence measured (radians): 89.5 deg
LAST_THETA = np.radians(89.5)
#: neighbouring incidences near the horizon are at most this ratio of cosines apart
GRAZING_RATIO = 2.0
#: Rec. 709 luminance of linear RGB
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


@dataclasses.dataclass(frozen=True)
class Resolution:
    """The tables' sizes: ``ndf`` theta nodes of the NDF and sigma, ``theta_i``
    incidences, ``vndf`` nodes per side of each VNDF, ``grid`` nodes per side of the
    adapted grid (luminance and colour values). Anisotropic files also measure azimuths
    of incidence, ``phi_i`` steps per quarter turn (4: every 22.5 deg), and hold an NDF of
    ``ndf_phi`` azimuths x ``ndf_aniso`` polar angles."""
    ndf: int = 128
    theta_i: int = 16
    vndf: int = 64
    grid: int = 64
    phi_i: int = 4
    ndf_aniso: int = 64
    ndf_phi: int = 33

    def size_bytes(self, channels=3, isotropic=True):
        """The file's size: its tables in float32, and about 500 bytes of header."""
        n_phi = 1 if isotropic else 4 * self.phi_i + 1
        ndf = 2 * 2 * self.ndf if isotropic else 2 * self.ndf_phi * self.ndf_aniso
        floats = (ndf + self.theta_i + n_phi + n_phi * self.theta_i * self.vndf ** 2
                  + n_phi * self.theta_i * (1 + channels) * self.grid ** 2)
        return 4 * floats + 500


def _azimuthal_cosine(a, b):
    """The integral over phi in [0, 2 pi) of max(0, a + b cos(phi)), b >= 0."""
    a, b = np.broadcast_arrays(np.asarray(a, float), np.asarray(b, float))
    with np.errstate(divide="ignore", invalid="ignore"):
        phi0 = np.arccos(np.clip(-a / np.where(b > 0, b, 1), -1, 1))
        partial = 2 * (a * phi0 + b * np.sin(phi0))
    return np.where(a >= b, 2 * np.pi * a, np.where(a <= -b, 0.0, partial))


def _theta_nodes(n):
    """The NDF grid's polar angles and their trapezoidal solid-angle weights (per unit
    azimuth): theta = u^2 pi / 2, dtheta = pi u du."""
    u = np.linspace(0, 1, n)
    theta = warp.u2theta(u)
    w = np.full(n, 1 / (n - 1))
    w[[0, -1]] /= 2
    return theta, w * np.pi * u * np.sin(theta)


def projected_area(theta_w, theta, weights, d):
    """sigma(w) = integral of <w, m>+ D(m) dm for an isotropic D given at polar angles
    ``theta`` with quadrature ``weights``, for incidences at polar angles ``theta_w``."""
    a = np.cos(theta_w)[:, None] * np.cos(theta)[None]
    b = np.sin(theta_w)[:, None] * np.sin(theta)[None]
    return _azimuthal_cosine(a, b) @ (weights * d)


def power_iteration(retro, theta, weights, tol=1e-9, max_iter=500):
    """The NDF (isotropic, at ``theta``) whose retro-reflection is ``retro``: the dominant
    eigenvector of D -> retro * sigma[D], scaled so that sigma(0) = 1. Returns (D, sigma
    at theta, iterations)."""
    kernel = _azimuthal_cosine(np.cos(theta)[:, None] * np.cos(theta)[None],
                               np.sin(theta)[:, None] * np.sin(theta)[None]) * weights
    d = np.ones_like(retro)
    for it in range(1, max_iter + 1):
        new = retro * (kernel @ d)
        peak = new.max()
        if not peak > 0:
            raise ValueError("the source reflects nothing back towards the light "
                             "(retro-reflection 0 everywhere): no NDF to measure")
        new /= peak
        change = np.max(np.abs(new - d))
        d = new
        if change < tol:
            break
    sigma = kernel @ d
    norm = sigma[0]
    return d / norm, sigma / norm, it


def _retro_directions(theta):
    return warp.spherical(theta, np.zeros_like(theta))


def _sigma_rule(sigma_of, n, last=LAST_THETA):
    """n incidences: theta_0 = 0 and theta_k where sigma falls to 1 - k/(n-1) (1 -
    sigma(last)), the last one at ``last`` (sigma decreasing in theta)."""
    fine = np.linspace(0, last, 2048)
    s = np.minimum.accumulate(sigma_of(fine))
    targets = 1 - np.arange(n) / (n - 1) * (1 - s[-1])
    # np.interp needs increasing abscissae: sigma decreases
    theta = np.interp(-targets, -s, fine)
    theta[0], theta[-1] = 0.0, last
    return np.maximum.accumulate(theta)


def _grazing(theta):
    """``theta`` with nodes added where the cosines of neighbours differ by more than
    ``GRAZING_RATIO`` (evenly in log cos between them)."""
    out = [theta[0]]
    for a, b in zip(theta[:-1], theta[1:]):
        ratio = np.cos(a) / max(np.cos(b), 1e-12)
        k = int(np.ceil(np.log(ratio) / np.log(GRAZING_RATIO) - 1e-9)) if ratio > 1 else 1
        c = np.cos(a) * ratio ** (-np.arange(1, max(k, 1)) / max(k, 1))
        out += list(np.arccos(c)) + [b]
    return np.array(out)


def _incidences(sigma_of, n, last=LAST_THETA):
    """n incidences: the sigma rule (``_sigma_rule``, the paper's) with fewer nodes, and
    nodes towards the horizon where the rule leaves neighbours whose cosines differ by
    more than ``GRAZING_RATIO`` (``_grazing``): there ``measured`` interpolates its
    tables linearly between incidences, and a lobe's values change as 1 / cos(theta_i)."""
    for k in range(n - 2):
        theta = _grazing(_sigma_rule(sigma_of, n - k, last))
        if len(theta) <= n:
            return refine(theta, n, last)
    return _sigma_rule(sigma_of, n, last)


def refine(nodes, n, last=LAST_THETA):
    """At least n incidences that include ``nodes`` (those below ``last``) and ``last``:
    the widest gaps halved until there are n (an RGL source's own incidences, where its
    values are measured rather than interpolated)."""
    theta = sorted(set(float(t) for t in nodes if 0 <= t < last - 1e-6) | {0.0, float(last)})
    while len(theta) < n:
        k = int(np.argmax(np.diff(theta)))
        theta.insert(k + 1, 0.5 * (theta[k] + theta[k + 1]))
    return np.array(theta)


def _ndf_isotropic(evaluate, res):
    """(ndf, sigma) tables (2 equal rows x ``res.ndf``) and the power iterations."""
    theta, weights = _theta_nodes(res.ndf)
    dirs = _retro_directions(theta)
    retro = np.maximum(luminance(np.asarray(evaluate(dirs, dirs), float)
                                  .reshape(len(theta), -1)), 0)
    d, _, iterations = power_iteration(retro, theta, weights)
    d = (1 - UNIFORM_SHARE) * d + UNIFORM_SHARE / np.pi   # sigma(0) = 1 for D = 1 / pi
    sigma = projected_area(theta, theta, weights, d)
    return (np.tile(d.astype(np.float32), (2, 1)), np.tile(sigma.astype(np.float32), (2, 1)),
            iterations)


def _ndf_anisotropic(evaluate, res, tol=1e-9, max_iter=500):
    """(ndf, sigma) tables (``res.ndf_phi`` azimuths x ``res.ndf_aniso`` polar angles over
    the whole circle) by power iteration on the sphere's grid, and the iterations."""
    theta, wt = _theta_nodes(res.ndf_aniso)
    phi = warp.u2phi(np.linspace(0, 1, res.ndf_phi))
    wp = np.full(len(phi), 2 * np.pi / (len(phi) - 1))
    wp[[0, -1]] /= 2                                   # the two ends are one azimuth
    tt, pp = np.meshgrid(theta, phi)                   # rows: phi, columns: theta
    dirs = warp.spherical(tt.ravel(), pp.ravel())
    weights = np.outer(wp, wt).ravel()
    retro = np.maximum(luminance(np.asarray(evaluate(dirs, dirs), float)
                                  .reshape(len(dirs), -1)), 0)
    kernel = np.maximum(dirs @ dirs.T, 0) * weights
    d = np.ones(len(dirs))
    for it in range(1, max_iter + 1):
        new = retro * (kernel @ d)
        if not new.max() > 0:
            raise ValueError("the source reflects nothing back towards the light "
                             "(retro-reflection 0 everywhere): no NDF to measure")
        new /= new.max()
        change, d = np.max(np.abs(new - d)), new
        if change < tol:
            break
    d /= (kernel @ d)[0]                               # sigma(normal) = 1
    d = (1 - UNIFORM_SHARE) * d + UNIFORM_SHARE / np.pi
    sigma = kernel @ d
    shape = (len(phi), len(theta))
    return (d.reshape(shape).astype(np.float32), sigma.reshape(shape).astype(np.float32), it)


def acquire(evaluate, res=Resolution(), channels=3, description="", progress=None,
            incidences=None, isotropic=True):
    """The fields of an RGL file measuring ``evaluate`` (a function (wi, wo) -> eval, arrays
    (n, 3) -> (n, channels): f cos theta_o) on the grid ``res``; ``channels`` = 3 writes
    ``rgb``, otherwise pass ``wavelengths`` through ``fields`` yourself. ``incidences``:
    polar angles to measure at (``refine``d to ``res.theta_i``) instead of the sigma rule.
    ``isotropic=False`` measures azimuths of incidence too (an anisotropic file), in
    ``res.phi_i`` steps per quarter turn over the whole circle, both ends included (so
    that ``measured`` folds nothing: its folds into a half or a quarter turn pick the
    wrong azimuth for wi in the plane y = 0, see ``docs/check.md``). ``progress``: a
    function called with a note after each step (the command's bar). Returns ({name:
    array}, info) with info the numbers worth saying."""
    step = progress or (lambda note: None)
    # 1-3: retro-reflection, NDF, sigma
    ndf, sigma, iterations = (_ndf_isotropic(evaluate, res) if isotropic
                              else _ndf_anisotropic(evaluate, res))
    step("NDF")

    def sigma_at(theta_w, phi_w=None):   # as measured.cpp evaluates it: bilinear in u
        if phi_w is None:                # the mean over azimuths (the incidences' rule)
            return np.mean([sigma_at(theta_w, np.full(len(theta_w), p))
                            for p in warp.u2phi(np.linspace(0, 1, 9)[:-1])], axis=0)
        u = np.stack([warp.theta2u(theta_w), warp.phi2u(phi_w)], -1)
        return warp.bilinear(sigma, u)

    # 4: incidences
    theta_i = (_incidences(sigma_at, res.theta_i) if incidences is None
               else refine(incidences, res.theta_i)).astype(np.float32)
    phi_i = (np.zeros(1) if isotropic else
             np.linspace(-np.pi, np.pi, 4 * res.phi_i + 1)).astype(np.float32)
    slices = [(k, l) for k in range(len(phi_i)) for l in range(len(theta_i))]
    wis = {(k, l): warp.spherical(np.array([theta_i[l]], float),
                                  np.array([phi_i[k]], float))[0] for k, l in slices}
    sigma_i = {(k, l): float(sigma_at(np.array([theta_i[l]], float),
                                      np.array([phi_i[k]], float))[0]) for k, l in slices}
    # half vectors' azimuths: relative to the incidence's (isotropic), else absolute
    offset = {(k, l): (float(phi_i[k]) if isotropic else 0.0) for k, l in slices}
    # 5: VNDF per incidence, on its own (u_theta, u_phi) grid
    u = np.linspace(0, 1, res.vndf)
    ut, up = np.meshgrid(u, u)                      # rows: phi, columns: theta
    um = np.stack([ut.ravel(), up.ravel()], -1)
    d_um = warp.bilinear(ndf, um)
    jac = 2 * np.pi ** 2 * um[:, 0] * np.sin(warp.u2theta(um[:, 0]))
    vndf = np.empty((len(phi_i), len(theta_i), res.vndf, res.vndf), np.float32)
    for k, l in slices:
        h = warp.spherical(warp.u2theta(um[:, 0]), warp.u2phi(um[:, 1]) + offset[k, l])
        v = jac * np.maximum(h @ wis[k, l], 0) * d_um / sigma_i[k, l]
        vndf[k, l] = v.reshape(res.vndf, res.vndf)
    step("VNDF")
    # 6: values on the adapted grid: the source at each node, averaged over the node's
    # footprint where it is not smooth there
    warps = {(k, l): footprint.Warp(vndf[k, l], ndf, wis[k, l], sigma_i[k, l], offset[k, l])
             for k, l in slices}
    # (an anisotropic file's 17 times as many incidences keep to the coarsest sub-cells:
    # the finer ones would take minutes, and its error near the horizon is the azimuths')
    values, negative, evaluations, averaged = footprint.grid_values(
        evaluate, warps, slices, res.grid, (len(phi_i), len(theta_i), channels),
        footprint.REFINE_STEPS if isotropic else footprint.REFINE_STEPS[:1])
    for k, l in slices:
        values[k, l] = clip_keeping_albedo(values[k, l].reshape(channels, -1).T).T.reshape(
            values[k, l].shape)
    values = values.astype(np.float32)
    lum = luminance(np.moveaxis(values, 2, -1)).astype(np.float32)
    step("values")
    fields = {
        "description": description or "virtual measurement",
        "phi_i": phi_i,
        "theta_i": theta_i,
        "ndf": ndf,
        "sigma": sigma,
        "vndf": vndf,
        "luminance": lum,
        "rgb" if channels == 3 else "spectra": values,
        "jacobian": np.ones(1, np.uint8),
    }
    info = {"power_iterations": iterations, "negative_values_clipped": negative,
            "evaluations": evaluations, "nodes_averaged": averaged,
            "nodes": int(np.prod(values.shape[:2])) * res.grid ** 2, "isotropic": isotropic}
    return fields, info


def clip_keeping_albedo(values):
    """values (N, C) of one incidence's grid without negative entries, each channel's sum
    kept: negatives set to 0 and the channel's positive values scaled by (sum of values) /
    (sum of positive values), 0 if the former is not positive. On the adapted grid a
    channel's mean value is its directional albedo (the values are eval / pdf of the VNDF
    sampling), so this keeps each channel's albedo at the incidence, which clipping alone
    would raise (by 49 % in blue at normal incidence for RGL's vch_golden_yellow)."""
    values = np.asarray(values, float)
    positive = np.maximum(values, 0)
    total, kept = values.sum(0), positive.sum(0)
    with np.errstate(divide="ignore", invalid="ignore"):
        factor = np.where(kept > 0, np.maximum(total, 0) / np.where(kept > 0, kept, 1), 0)
    return positive * np.where((values < 0).any(0), factor, 1)


def luminance(values):
    """Luminance of RGB values (..., 3), the mean of other channels."""
    values = np.asarray(values, float)
    if values.shape[-1] == 3:
        return values @ LUMINANCE
    return values.mean(-1)
