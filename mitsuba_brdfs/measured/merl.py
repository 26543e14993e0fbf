"""Measured isotropic BRDFs in MERL's binary format (Matusik et al. 2003).

A file holds three int32 dimensions (n_theta_h, n_theta_d, n_phi_d), 90 x 90 x 180 for the
MERL database, then the red, green and blue tables, each n_theta_h n_theta_d n_phi_d
float64 in C order (phi_d fastest). A table entry times the channel's scale (1/1500,
1.15/1500, 1.66/1500) is the BRDF f (without cosine); negative entries mark bins that were
not measured. The bins are those of the Rusinkiewicz half/difference angles: theta_h is
indexed non-linearly, index = sqrt(theta_h / (pi/2)) n_theta_h, theta_d and phi_d
linearly over [0, pi/2) and [0, pi) (reciprocity folds phi_d to half a turn).

``directions`` places each bin's sample where the value stands for: at the centre of its
cell in the file's own coordinates (theta_h = ((i + 1/2) / n)^2 pi/2, theta_d = (j + 1/2) /
n pi/2, phi_d = (k + 1/2) / n pi), the centre of the cell that MERL's reader
(``BRDFRead.cpp``, ``lookup_brdf_val``) maps a direction to with floor(), as ALTA's reader
of the format does. ``lookup`` is that mapping, so every bin's centre reads back as its
own bin. ``position = "edge"`` gives the lower edge of the cell (i / n, ...) as the BRDF
benchmark's MERL linearizer computes it (its comment says "centre"): one direction in
three there reads back as a neighbouring bin by rounding, and the values describe the
wrong directions by half a cell (docs/presets.md measures what that does to a fit). Other
dimensions than 90 x 90 x 180 are read and written too (small files for tests).
``from_bsdf`` evaluates a BSDF at the bins' directions: a MERL file of a known BRDF;
``evaluator`` gives f cos of a MERL file at any direction pairs; ``kind`` tells a MERL file
from an RGL one by their content.

References: W. Matusik, H. Pfister, M. Brand, L. McMillan, "A Data-Driven Reflectance Model",
SIGGRAPH 2003 (the database and its reader, ``BRDFRead.cpp``); S. Rusinkiewicz, "A New
Change of Variables for Efficient BRDF Representation", EGWR 1998; ALTA
(https://github.com/belcour/alta, ``sources/plugins/data_io/merl.cpp``, MERL's reader
with the bins' centres); the BRDF benchmark (https://github.com/bsdfbenchmark/bbm,
``include/linearizer/merl_linearizer.h``).
"""
import os

import numpy as np

__all__ = ["DIMS", "SCALE", "POSITIONS", "expected_size", "check_file", "kind", "read",
           "evaluator", "write",
           "directions", "lookup", "measure", "from_bsdf"]

#: the database's resolution (theta_h, theta_d, phi_d)
DIMS = (90, 90, 180)
#: factor from a table entry to the BRDF, per channel (MERL's BRDFRead.cpp)
SCALE = np.array([1.0 / 1500, 1.15 / 1500, 1.66 / 1500])
_HEADER = 3 * 4
#: where ``directions`` puts a bin's sample in its cell: the centre (what the value stands
#: for), or the lower edge (the BRDF benchmark's linearizer)
POSITIONS = ("centre", "edge")


def expected_size(dims):
    """Bytes of a file of these dimensions: the header and three float64 tables."""
    return _HEADER + 3 * 8 * int(np.prod(dims))


def check_file(path):
    """The dimensions of a MERL file, or ValueError saying why it is not one (the
    expected and actual sizes for a truncated or padded file)."""
    if os.path.isdir(path):
        raise ValueError(f"{path}: a folder, not a MERL file (give one .binary file)")
    if not os.path.isfile(path):
        raise ValueError(f"{path}: no such file")
    size = os.path.getsize(path)
    if size < _HEADER:
        raise ValueError(f"{path}: not a MERL BRDF: {size} bytes, shorter than its "
                         f"{_HEADER}-byte header")
    with open(path, "rb") as f:
        dims = tuple(int(d) for d in np.frombuffer(f.read(_HEADER), dtype="<i4"))
    if not all(0 < d <= 100_000 for d in dims):
        raise ValueError(f"{path}: not a MERL BRDF: header dimensions {dims} (expected "
                         f"positive sizes such as {DIMS})")
    expected = expected_size(dims)
    if size != expected:
        raise ValueError(f"{path}: a MERL BRDF of {dims[0]} x {dims[1]} x {dims[2]} bins "
                         f"has {expected} bytes (12 + 3 x 8 x {int(np.prod(dims))}); this "
                         f"file has {size}")
    return dims


def kind(path):
    """"rgl" or "merl", by the file's content (an RGL file by its ``tensor_file`` header, a
    MERL file by its size); ``tensor.FormatError`` (a ``ValueError``) naming the file for a
    folder, a missing file or anything else."""
    from .tensor import FormatError, is_tensor_file
    path = os.fspath(path)
    if os.path.isdir(path):
        raise FormatError(f"{path}: a folder, not a measured file (give one RGL .bsdf or "
                          f"MERL .binary file)")
    if not os.path.isfile(path):
        raise FormatError(f"{path}: no such file")
    if is_tensor_file(path):
        return "rgl"
    try:
        check_file(path)
    except ValueError as e:
        raise FormatError(f"{path}: neither an RGL file (it does not start with "
                          f"'tensor_file') nor a MERL file ({str(e).split(': ', 1)[-1]})") from None
    return "merl"


def read(path):
    """(dims, f): f has shape (n, 3), the BRDF in bin order, NaN where not measured."""
    dims = check_file(path)
    n = int(np.prod(dims))
    raw = np.fromfile(path, dtype="<f8", offset=_HEADER, count=3 * n).reshape(3, n).T
    f = raw * SCALE
    f[raw < 0] = np.nan
    return dims, f


def evaluator(path):
    """(evaluate, dims, unmeasured bins) of the MERL file ``path``: evaluate(wi, wo) -> f cos
    theta_o (n, 3), its table looked up as MERL's reader does (``lookup``), unmeasured bins
    as 0, 0 below the horizon."""
    dims, f = read(path)
    unmeasured = int(np.isnan(f).any(1).sum())
    table = np.nan_to_num(f, nan=0.0)

    def evaluate(wi, wo):
        wi, wo = np.asarray(wi, float), np.asarray(wo, float)
        out = np.zeros((len(wi), 3))
        up = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        if up.any():
            out[up] = table[lookup(wi[up], wo[up], dims)] * wo[up, 2:3]
        return out
    return evaluate, dims, unmeasured


def write(path, f, dims=DIMS):
    """Write f (shape (n, 3), the BRDF in bin order; NaN = not measured) as a MERL file."""
    f = np.asarray(f, float).reshape(-1, 3)
    if len(f) != int(np.prod(dims)):
        raise ValueError(f"{len(f)} values for {dims[0]} x {dims[1]} x {dims[2]} bins")
    raw = np.where(np.isnan(f), -1.0, f / SCALE)
    with open(path, "wb") as out:
        out.write(np.asarray(dims, dtype="<i4").tobytes())
        out.write(np.ascontiguousarray(raw.T, dtype="<f8").tobytes())


def _angles(dims, index=None, position="centre"):
    """(theta_h, theta_d, phi_d) of the bins ``index`` (all by default), at ``position``."""
    if position not in POSITIONS:
        raise ValueError(f"position must be one of {', '.join(POSITIONS)}, got {position!r}")
    nh, nd, nphi = dims
    index = np.arange(int(np.prod(dims))) if index is None else np.asarray(index)
    i, j, k = np.unravel_index(index, dims)
    o = 0.5 if position == "centre" else 0.0
    return ((i + o) / nh) ** 2 * (np.pi / 2), (j + o) / nd * (np.pi / 2), (k + o) / nphi * np.pi


def directions(dims=DIMS, phi_h=None, index=None, position="centre"):
    """(wi, wo), each (n, 3) float64, of every bin in file order (or of the bins ``index``),
    from its half/difference angles at ``position`` in its cell (``POSITIONS``); ``phi_h``
    (n,) turns each pair about the normal (an isotropic BRDF does not change; 0 by
    default)."""
    theta_h, theta_d, phi_d = _angles(dims, index, position)
    st, ct = np.sin(theta_d), np.cos(theta_d)
    d = np.stack([st * np.cos(phi_d), st * np.sin(phi_d), ct], -1)   # in the frame of h
    sh, ch = np.sin(theta_h), np.cos(theta_h)
    # rotate by theta_h about y: h = (sin theta_h, 0, cos theta_h)
    wi = np.stack([d[:, 0] * ch + d[:, 2] * sh, d[:, 1], -d[:, 0] * sh + d[:, 2] * ch], -1)
    h = np.stack([sh, 0 * sh, ch], -1)
    wo = 2 * np.sum(wi * h, axis=1, keepdims=True) * h - wi
    if phi_h is not None:
        c, s = np.cos(phi_h)[:, None], np.sin(phi_h)[:, None]
        rot = lambda v: np.concatenate([c * v[:, :1] - s * v[:, 1:2],
                                        s * v[:, :1] + c * v[:, 1:2], v[:, 2:]], 1)
        wi, wo = rot(wi), rot(wo)
    return wi, wo


def lookup(wi, wo, dims=DIMS):
    """The bin index of each direction pair, as MERL's reader finds it (``lookup_brdf_val``:
    the half vector's polar angle, the difference vector's angles in the half vector's
    frame, each index the floor of its coordinate, phi_d folded to [0, pi) by
    reciprocity)."""
    wi, wo = np.asarray(wi, float), np.asarray(wo, float)
    h = wi + wo
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    theta_h = np.arccos(np.clip(h[:, 2], -1, 1))
    phi_h = np.arctan2(h[:, 1], h[:, 0])
    c, s = np.cos(-phi_h), np.sin(-phi_h)
    v = np.stack([c * wi[:, 0] - s * wi[:, 1], s * wi[:, 0] + c * wi[:, 1], wi[:, 2]], -1)
    ct, st = np.cos(-theta_h), np.sin(-theta_h)
    d = np.stack([v[:, 0] * ct + v[:, 2] * st, v[:, 1], -v[:, 0] * st + v[:, 2] * ct], -1)
    theta_d = np.arccos(np.clip(d[:, 2], -1, 1))
    phi_d = np.arctan2(d[:, 1], d[:, 0])
    phi_d = np.where(phi_d < 0, phi_d + np.pi, phi_d)
    nh, nd, nphi = dims
    i = np.clip(np.floor(np.sqrt(theta_h / (np.pi / 2)) * nh), 0, nh - 1)
    j = np.clip(np.floor(theta_d / (np.pi / 2) * nd), 0, nd - 1)
    k = np.clip(np.floor(phi_d / np.pi * nphi), 0, nphi - 1)
    return ((i * nd + j) * nphi + k).astype(np.int64)


def measure(dims=DIMS, index=None):
    """The measure of each bin's cell (all bins, or those of ``index``) in the space of
    direction pairs, dw_i dw_o = 4 cos(theta_d) dw_h dw_d (Rusinkiewicz 1998), integrated
    exactly over the cell and phi_h, times 2 for the half turn of phi_d that reciprocity
    folds in. Summed over all bins, 8 pi^2: (2 pi)^2 for the pairs of directions above
    the horizon (the bins whose centres are above it sum to that within 2e-4) and as
    much for pairs with a direction below it, which the format's domain covers too. Bins
    near theta_h = 0 are tiny (theta_h is indexed by its square root): a sum over bins
    weighted by this is an integral over the direction pairs."""
    nh, nd, nphi = dims
    index = np.arange(int(np.prod(dims))) if index is None else np.asarray(index)
    i, j, k = np.unravel_index(index, dims)
    th = lambda a: (a / nh) ** 2 * (np.pi / 2)
    td = lambda a: a / nd * (np.pi / 2)
    h = np.cos(th(i)) - np.cos(th(i + 1))                     # int sin theta_h
    d = (np.sin(td(j + 1)) ** 2 - np.sin(td(j)) ** 2) / 2     # int cos theta_d sin theta_d
    return 4 * h * d * (np.pi / nphi) * (2 * np.pi) * 2


def from_bsdf(bsdf, dims=DIMS, position="centre"):
    """f (shape (n, 3), bin order) of a loaded BSDF (RGB variant) at the bins' directions
    (``directions`` at ``position``): NaN, unmeasured, where a direction is within 1e-6 of
    the horizon or below it. ``write(path, from_bsdf(bsdf, dims), dims)`` is a MERL file of
    that BSDF."""
    from ..validate.probe import eval_np
    wi, wo = directions(dims, position=position)
    ok = (wi[:, 2] > 1e-6) & (wo[:, 2] > 1e-6)
    f = np.full((len(wi), 3), np.nan)
    f[ok] = eval_np(bsdf, wi[ok], wo[ok]) / wo[ok][:, 2:3]
    return f
