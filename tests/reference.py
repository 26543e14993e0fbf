"""Independent float64 NumPy transcriptions of the seed formulas, for tests.

Written straight from the papers' equations (with trigonometric angles where the paper has
them), sharing no code with the package. Directions are unit vectors in the local frame
(n = z, u = x, v = y), arrays of shape (N, 3).
"""
import numpy as np


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def ashikhmin_shirley(k1, k2, rs, rd, nu, nv):
    """AS 2000 eq. 1-5: rho(k1, k2), without the cosine. rs, rd: scalars or (3,) colours.

    Returns (specular, diffuse), each of shape (N, C)."""
    k1, k2 = np.asarray(k1, float), np.asarray(k2, float)
    rs = np.atleast_1d(np.asarray(rs, float))[None, :]
    rd = np.atleast_1d(np.asarray(rd, float))[None, :]
    h = _unit(k1 + k2)
    cos_th = h[:, 2]
    phi = np.arctan2(h[:, 1], h[:, 0])
    expo = nu * np.cos(phi) ** 2 + nv * np.sin(phi) ** 2                # eq. 2
    kh = np.sum(k1 * h, axis=1)
    F = rs + (1 - rs) * (1 - kh[:, None]) ** 5                          # eq. 3
    n1, n2 = k1[:, 2], k2[:, 2]
    spec = (np.sqrt((nu + 1) * (nv + 1)) / (8 * np.pi) * cos_th ** expo
            / (kh * np.maximum(n1, n2)))[:, None] * F
    diff = (28 * rd / (23 * np.pi) * (1 - rs)
            * ((1 - (1 - n1 / 2) ** 5) * (1 - (1 - n2 / 2) ** 5))[:, None])  # eq. 5
    return spec, diff


def ashikhmin_shirley_half_pdf(h, nu, nv):
    """AS 2000 eq. 6 in spherical angles."""
    h = np.asarray(h, float)
    phi = np.arctan2(h[:, 1], h[:, 0])
    expo = nu * np.cos(phi) ** 2 + nv * np.sin(phi) ** 2
    return np.sqrt((nu + 1) * (nv + 1)) / (2 * np.pi) * np.clip(h[:, 2], 0, None) ** expo
