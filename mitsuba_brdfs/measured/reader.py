"""One reader for measured files: ``read(path)`` gives the measured samples of an RGL file
(recognised by its ``tensor_file`` header) or a MERL file (recognised by its size), as a
``rgl.Samples``: direction pairs, the BRDF f (without cosine) per channel, and what a fit
needs besides (``kind``, ``wavelengths``, the incidence of each RGL sample).

A file that is neither, or a truncated one, raises ``FormatError`` (a ``ValueError``) in one
line naming the file: the commands exit with status 2.

MERL: every measured bin (finite, both directions above the horizon by more than
``min_cos``) at the directions ``merl.directions`` gives its bin (phi_h = 0: an isotropic
BRDF does not depend on it).
"""
import os

import numpy as np

from .merl import kind
from .rgl import Samples, read_samples
from .tensor import FormatError

__all__ = ["read", "kind"]


def read(path, min_cos=1e-4):
    """The ``Samples`` of an RGL or MERL file."""
    path = os.fspath(path)
    if kind(path) == "rgl":
        s = read_samples(path, min_cos)
        s.kind = "rgl"
        return s
    from . import merl
    dims, f = merl.read(path)
    wi, wo = merl.directions(dims)
    keep = np.isfinite(f).all(1) & (wi[:, 2] > min_cos) & (wo[:, 2] > min_cos)
    if not keep.any():
        raise FormatError(f"{path}: no measured bin above the horizon")
    return Samples(path=path, description=f"MERL {os.path.basename(path)}", wi=wi[keep],
                   wo=wo[keep], value=f[keep], incidence=None, phi_index=None, theta_i=None,
                   phi_i=None, wavelengths=None, isotropic=True, kind="merl")
