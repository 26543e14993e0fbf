"""RGL material files: Dupuy & Jakob's adaptive parameterization, as Mitsuba's ``measured``
plugin reads it, and the measured samples they hold.

An RGL file (``*_rgb.bsdf``, ``*_spec.bsdf``) is a tensor file (``measured.tensor``) with
the fields ``measured.cpp`` requires (``FIELDS``; ``load`` checks each, with the checks of
``measured.cpp`` and the size relations between them, and names the field that fails):

- ``theta_i`` (n_theta), ``phi_i`` (n_phi): the incidences measured (radians); at most two
  azimuths make an isotropic material;
- ``ndf``, ``sigma`` (n_phi_m, n_theta_m): the microfacet distribution D and the projected
  area sigma(w) = integral of <w, m> D(m) dm, on the unit square of (theta, phi)
  (``measured.warp``: u = sqrt(2 theta / pi));
- ``vndf`` (n_phi, n_theta, h, w): per incidence, the visible-normal density over the
  half vector's square, warped by ``warp.Marginal2D``;
- ``luminance`` (n_phi, n_theta, n, n) and ``rgb`` (n_phi, n_theta, 3, n, n), or
  ``spectra`` (.., n_lambda, n, n) with ``wavelengths`` (nm): the measured values on a
  regular n x n grid of the VNDF warp's *input* square (the "adapted grid");
- ``description`` (text), ``jacobian`` (uint8: 1 when the values are stored divided by
  D(m) / (4 sigma(wi)), so that eval = value * D / (4 sigma), as in every RGL file).

Mitsuba ignores the other fields (``version``; ``valid``, a bit mask whose meaning differs
between the database's files: in some it marks the grid nodes whose outgoing direction is
above the horizon, in others their complement; ``samples`` ignores it and keeps the
nodes above the horizon).

``samples`` gives what a fit needs: the measured direction pairs and values, f(wi, wo)
(without the cosine, as ``merl.read``), one row per grid node of every incidence whose
outgoing direction lies above the horizon. Each is read from the tables: the node's
table value times D(m) / (4 sigma(wi)) / cos(theta_o), at the direction the VNDF warp maps
the node to; this is exactly what ``measured``'s eval returns there, as
``tests/test_measured.py`` shows (agreement to float32 rounding).

Negative values: RGB files hold negative entries where a measured colour lies outside the
sRGB gamut (see ``docs/measured.md``); ``samples`` returns them as Mitsuba renders them,
and says how many (``Samples.negative``); ``clip_negative`` gives the nearest non-negative
colours.

References: J. Dupuy, W. Jakob, "An Adaptive Parameterization for Efficient Material
Acquisition and Rendering", ACM TOG 37(6) (SIGGRAPH Asia 2018).
"""
import dataclasses
import os

import numpy as np

from . import tensor, warp
from .warp import node_grid
from .tensor import FormatError

__all__ = ["FIELDS", "Material", "Samples", "load", "load_for_variant", "check_fields",
           "samples", "read_samples", "clip_negative", "node_grid"]

#: field -> (rank, dtype) that ``measured.cpp`` requires (``rgb`` or ``spectra`` and
#: ``wavelengths`` besides)
FIELDS = {"description": (1, "uint8"), "theta_i": (1, "float32"), "phi_i": (1, "float32"),
          "ndf": (2, "float32"), "sigma": (2, "float32"), "vndf": (4, "float32"),
          "luminance": (4, "float32"), "jacobian": (1, "uint8")}


@dataclasses.dataclass
class Material:
    """An RGL file's tables (float64 copies) and what they describe."""
    path: str
    description: str
    theta_i: np.ndarray
    phi_i: np.ndarray
    ndf: np.ndarray
    sigma: np.ndarray
    vndf: np.ndarray
    luminance: np.ndarray
    values: np.ndarray          # (n_phi, n_theta, channels, n, n): rgb or spectra
    wavelengths: np.ndarray     # None for an RGB file
    jacobian: bool
    fields: dict                # every field as read

    @property
    def spectral(self):
        return self.wavelengths is not None

    @property
    def isotropic(self):
        return len(self.phi_i) <= 2

    @property
    def resolution(self):
        """(n_phi, n_theta, n, n): incidences and the adapted grid of each."""
        s = self.values.shape
        return s[0], s[1], s[3], s[4]


def _describe(shape, dtype):
    return f"{' x '.join(map(str, shape))} {dtype}"


def check_fields(fields, path):
    """Raise ``FormatError`` naming the first field ``measured.cpp`` would refuse (missing,
    of the wrong rank or type, or of a size that does not match the others)."""
    spectral = "wavelengths" in fields
    need = dict(FIELDS, **({"spectra": (5, "float32"), "wavelengths": (1, "float32")}
                           if spectral else {"rgb": (5, "float32")}))
    kind = "a spectral" if spectral else "an RGB"
    for name, (rank, dtype) in need.items():
        if name not in fields:
            raise FormatError(f"{path}: not an RGL material file: {kind} one needs the field "
                              f"'{name}' (it has {', '.join(fields) or 'no field'})")
        a = fields[name]
        if a.ndim != rank or a.dtype != np.dtype(dtype):
            raise FormatError(f"{path}: RGL field '{name}' is {_describe(a.shape, a.dtype)}; "
                              f"measured needs rank {rank}, {dtype}")
    table = fields["spectra" if spectral else "rgb"]
    n_phi, n_theta = len(fields["phi_i"]), len(fields["theta_i"])
    lum, vndf = fields["luminance"], fields["vndf"]
    channels = len(fields["wavelengths"]) if spectral else 3
    rules = [
        ("vndf", vndf.shape[:2] == (n_phi, n_theta), "(phi_i, theta_i, ...)"),
        ("luminance", lum.shape[:2] == (n_phi, n_theta) and lum.shape[2] == lum.shape[3],
         "(phi_i, theta_i, n, n)"),
        ("spectra" if spectral else "rgb",
         table.shape[:3] == (n_phi, n_theta, channels) and table.shape[3:] == lum.shape[2:],
         f"(phi_i, theta_i, {channels}, n, n) with the luminance's n"),
        ("jacobian", fields["jacobian"].shape == (1,), "(1,)")]
    for name, ok, expected in rules:
        if not ok:
            a = fields[name]
            raise FormatError(f"{path}: RGL field '{name}' is {_describe(a.shape, a.dtype)}; "
                              f"measured needs {expected}")
    for name in ("ndf", "sigma", "vndf", "luminance"):
        if min(fields[name].shape[-2:]) < 2:
            a = fields[name]
            raise FormatError(f"{path}: RGL field '{name}' is {_describe(a.shape, a.dtype)}: "
                              f"a table needs at least 2 x 2 nodes")
    for name in ("theta_i", "phi_i"):
        a = fields[name]
        if len(a) == 0 or not np.isfinite(a).all() or (np.diff(a) <= 0).any():
            raise FormatError(f"{path}: RGL field '{name}' must hold increasing finite "
                              f"angles, it holds {np.round(a, 4).tolist()}")
    finite = [k for k in ("ndf", "sigma", "vndf", "luminance") if not np.isfinite(fields[k]).all()]
    if finite:
        raise FormatError(f"{path}: RGL field '{finite[0]}' holds NaN or infinite values")


def load(path):
    """The ``Material`` of an RGL file; ``FormatError`` for anything else."""
    path = os.fspath(path)
    fields = tensor.read(path)
    check_fields(fields, path)
    spectral = "wavelengths" in fields
    f64 = {k: np.asarray(v, float) for k, v in fields.items() if v.dtype.kind == "f"}
    return Material(
        path=path, description=bytes(fields["description"]).decode("utf-8", "replace"),
        theta_i=f64["theta_i"], phi_i=f64["phi_i"], ndf=f64["ndf"], sigma=f64["sigma"],
        vndf=f64["vndf"], luminance=f64["luminance"],
        values=f64["spectra" if spectral else "rgb"],
        wavelengths=f64["wavelengths"] if spectral else None,
        jacobian=bool(fields["jacobian"][0]), fields=fields)


def load_for_variant(path, command=""):
    """``load(path)`` where the active variant is of the file's kind, as Mitsuba's
    ``measured`` reads it (RGB files in RGB variants, spectral ones in spectral variants);
    else ``FormatError`` in one line naming the variant to use (``command``: the command
    whose ``--variant`` it names, e.g. "explore")."""
    import mitsuba as mi
    material = load(path)
    use = f"{command} --variant".lstrip()
    if material.spectral and not mi.is_spectral:
        raise FormatError(f"{path}: a spectral RGL file: Mitsuba's measured reads it in "
                          f"spectral variants only ({use} llvm_ad_spectral)")
    if not material.spectral and not mi.is_rgb:
        raise FormatError(f"{path}: an RGB RGL file: Mitsuba's measured reads it in RGB "
                          f"variants only ({use} llvm_ad_rgb)")
    return material


@dataclasses.dataclass
class Samples:
    """Measured samples of an RGL file: what a fit reads.

    ``wi``, ``wo`` (n, 3) float64 local directions (z the normal); ``value`` (n, C) the BRDF
    f(wi, wo) without the cosine (C = 3 for RGB, one per wavelength otherwise), as Mitsuba's
    ``measured`` evaluates it (its eval divided by cos theta_o); ``incidence`` (n,) the
    index into ``theta_i`` (and ``phi_index`` into ``phi_i``) of each sample (None for a
    MERL file); ``wavelengths`` (nm) or None for RGB; ``kind``: "rgl" or "merl";
    ``negative``: how many values are below 0; ``solid_angle`` (n,): the solid angle of
    outgoing directions each sample stands for (the sum of f cos theta_o times it over an
    incidence's samples is the directional albedo there), None for a MERL file."""
    path: str
    description: str
    wi: np.ndarray
    wo: np.ndarray
    value: np.ndarray
    incidence: np.ndarray
    phi_index: np.ndarray
    theta_i: np.ndarray
    phi_i: np.ndarray
    wavelengths: np.ndarray
    isotropic: bool
    kind: str = "rgl"
    solid_angle: np.ndarray = None

    @property
    def spectral(self):
        return self.wavelengths is not None

    @property
    def negative(self):
        return int((self.value < 0).sum())

    @property
    def eval(self):
        """f cos theta_o: what a BSDF's eval returns."""
        return self.value * self.wo[:, 2:3]


def _slice_directions(m, k, l, nodes):
    """wi (3,), the half vectors (N, 3), their unit coordinates u_m, the outgoing
    directions of the grid ``nodes`` at incidence (phi_i[k], theta_i[l]) and the solid
    angle of outgoing directions each node stands for (N,)."""
    theta_i, phi_i = m.theta_i[l], m.phi_i[k]
    wi = warp.spherical(np.array([theta_i]), np.array([phi_i]))[0]
    u_m, density = warp.Marginal2D(m.vndf[k, l]).sample(nodes)
    phi_m = warp.u2phi(u_m[:, 1]) + (phi_i if m.isotropic else 0.0)
    theta_m = warp.u2theta(u_m[:, 0])
    h = warp.spherical(theta_m, phi_m)
    wo = 2 * (h @ wi)[:, None] * h - wi
    # the node's cell of the warp's input square (trapezoidal: halves on the edges), in
    # u_m by the warp's density, in half vectors by d omega_h = sin(theta) dtheta dphi
    # (dtheta = pi u du, dphi = 2 pi dv), in outgoing directions by 4 |wi.h|
    n = int(round(np.sqrt(len(nodes))))
    edge = np.where((nodes == 0) | (nodes == 1), 0.5, 1.0).prod(1) / (n - 1) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        d_h = edge / density * np.sin(theta_m) * np.pi * u_m[:, 0] * 2 * np.pi
    d_o = np.where(density > 0, 4 * np.abs(h @ wi) * d_h, 0.0)
    return wi, h, u_m, wo, d_o


def samples(m, min_cos=1e-4):
    """The measured samples of a ``Material`` (or a path): every node of the adapted grid
    of every incidence with both directions more than ``min_cos`` above the horizon."""
    if not isinstance(m, Material):
        m = load(m)
    n_phi, n_theta, n, _ = m.resolution
    nodes = node_grid(n)
    out = {k: [] for k in ("wi", "wo", "value", "incidence", "phi_index", "solid_angle")}
    for k in range(n_phi):
        for l in range(n_theta):
            wi, h, u_m, wo, d_o = _slice_directions(m, k, l, nodes)
            keep = (wo[:, 2] > min_cos) & (wi[2] > min_cos)
            if not keep.any():
                continue
            table = m.values[k, l].reshape(m.values.shape[2], -1).T[keep]   # (N, C)
            if m.jacobian:
                u_wi = np.array([[warp.theta2u(m.theta_i[l]), warp.phi2u(m.phi_i[k])]])
                d = warp.bilinear(m.ndf, u_m[keep])
                table = table * (d / (4 * warp.bilinear(m.sigma, u_wi)))[:, None]
            out["wi"].append(np.broadcast_to(wi, (keep.sum(), 3)))
            out["wo"].append(wo[keep])
            out["value"].append(table / wo[keep][:, 2:3])
            out["incidence"].append(np.full(keep.sum(), l))
            out["phi_index"].append(np.full(keep.sum(), k))
            out["solid_angle"].append(d_o[keep])
    if not out["wi"]:
        raise FormatError(f"{m.path}: no measured direction above the horizon")
    cat = {k: np.concatenate(v) for k, v in out.items()}
    return Samples(path=m.path, description=m.description, theta_i=m.theta_i, phi_i=m.phi_i,
                   wavelengths=m.wavelengths, isotropic=m.isotropic, **cat)


def read_samples(path, min_cos=1e-4):
    """``samples`` of the RGL file at ``path``."""
    return samples(load(path), min_cos)


def clip_negative(value):
    """The nearest non-negative values (each channel clipped at 0): the L2 projection onto
    the colours a reflectance model can produce."""
    return np.maximum(value, 0.0)
