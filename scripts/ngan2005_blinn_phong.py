"""Which lobe the Ngan et al. 2005 Blinn-Phong fits describe: mirror or half vector.

For every material of ``mitsuba_brdfs.presets``, the specular albedo at normal incidence
(float64 quadrature over theta_h: theta_o = 2 theta_h, d(omega_o) = 4 cos(theta_h)
d(omega_h)) of each fit, and the Blinn-Phong exponent against the Ashikhmin-Shirley one and
Ward's equivalent 2 / m^2 - 2. Prints medians and interquartile ranges (docs/presets.md).

    python scripts/ngan2005_blinn_phong.py
"""
import numpy as np
from scipy.integrate import quad

from mitsuba_brdfs import presets


def _schlick(f0, c):
    return f0 + (1 - f0) * (1 - c) ** 5


def albedo0(lobe, width):
    g = lambda t: lobe(t) * np.cos(2 * t) * 4 * np.cos(t) * 2 * np.pi * np.sin(t)
    pts = [w for w in (width / 2, width, 2 * width, 4 * width, 8 * width, 16 * width)
           if w < np.pi / 4]
    return quad(g, 0, np.pi / 4, points=pts, limit=500, epsabs=1e-12)[0]


def lobes(material):
    """{model: specular albedo at normal incidence (channel mean)}."""
    pi, r = np.pi, {}
    p = presets.raw("ashikhmin_shirley", material)
    a, n, F0 = np.mean(p["albedo"]), p["sharpness"], p["fresnel"]
    r["ashikhmin_shirley"] = albedo0(lambda t: a * (n + 1) / (8 * pi) * np.cos(t) ** n
                                     * _schlick(F0, np.cos(t)) / np.cos(t), 1 / np.sqrt(n + 1))
    p = presets.raw("cook_torrance", material)
    a, m, F0 = np.mean(p["albedo"]), p["roughness"], p["fresnel"]
    D = lambda t: np.exp(-np.tan(t) ** 2 / m ** 2) / (pi * m * m * np.cos(t) ** 4)
    r["cook_torrance"] = albedo0(lambda t: a * D(t) * np.minimum(1, 2 * np.cos(2 * t))
                                 * _schlick(F0, np.cos(t)) / (pi * np.cos(2 * t)), m)
    for model, power in (("ward", 0.5), ("ward_duer", 1.0)):
        p = presets.raw(model, material)
        a, m = np.mean(p["albedo"]), p["roughness"]
        r[model] = albedo0(lambda t: a * np.exp(-np.tan(t) ** 2 / m ** 2)
                           / (4 * pi * m * m * np.cos(2 * t) ** power), m)
    p = presets.raw("blinn_phong", material)
    a, n = np.mean(p["albedo"]), p["sharpness"]
    r["mirror"] = albedo0(lambda t: a * (n + 2) / (2 * pi) * np.cos(2 * t) ** n, 0.5 / np.sqrt(n + 1))
    r["half"] = albedo0(lambda t: a * (n + 2) / (2 * pi) * np.cos(t) ** n, 1 / np.sqrt(n + 1))
    return r


def main():
    rows = {m: lobes(m) for m in presets.names()}
    four = ("ashikhmin_shirley", "cook_torrance", "ward", "ward_duer")
    mean4 = np.array([np.mean([r[k] for k in four]) for r in rows.values()])

    def show(label, values):
        q = np.percentile(values, [25, 50, 75])
        print(f"{label:44s} median {q[1]:.2f}  (interquartile {q[0]:.2f}-{q[2]:.2f})")

    for k in ("mirror", "half") + four:
        show(f"albedo of {k} / mean of the four others", np.array([r[k] for r in rows.values()]) / mean4)
    n_bp = np.array([presets.raw("blinn_phong", m)["sharpness"] for m in rows])
    n_as = np.array([presets.raw("ashikhmin_shirley", m)["sharpness"] for m in rows])
    n_w = np.array([2 / presets.raw("ward", m)["roughness"] ** 2 - 2 for m in rows])
    show("Blinn-Phong exponent / Ashikhmin-Shirley's", n_bp / n_as)
    show("Blinn-Phong exponent / Ward's 2 / m^2 - 2", n_bp / n_w)


if __name__ == "__main__":
    main()
