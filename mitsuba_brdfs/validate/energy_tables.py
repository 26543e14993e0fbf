"""The tables of energy compensation, measured with the plugins' own ``sample()``.

E(mu, r), the directional albedo of a white microfacet lobe (F = 1: ``f0 = 1`` for
``cook_torrance``, ``eta = 1e30`` for ``torrance_sparrow``, whose R0 rounds to 1), is the
mean sample weight at incidence mu. Each node of a table is the mean over a regular
``strata`` x ``strata`` grid of sample points (cell centres) rather than random ones: the
weights are bounded and piecewise smooth, so the grid's error falls about like
1 / strata^2 away from the lobe's edges and like 1 / strata where a sample leaves the
hemisphere (measured: ``scripts/energy_tables.py --compare``). All mu nodes of one
roughness are one kernel; the roughness (or exponent) changes through ``mi.traverse``, so
one lobe is one compiled kernel. ``core.energy`` describes the tables and looks them up.
"""
import datetime

import drjit as dr
import mitsuba as mi
import numpy as np

from ..core.energy import (N_MU, N_ROUGHNESS, exponent_of_roughness, mu_nodes,
                           one_minus_average, roughness_nodes, table_keys)

__all__ = ["STRATA", "lobe", "measure", "build"]

#: sample points per node along each axis of the shipped tables
STRATA = 1024


def lobe(key):
    """(BSDF dict of a white single-scattering lobe, its table parameter, its value at each
    roughness node) for table ``key``."""
    if key == "torrance_sparrow":
        return ({"type": "torrance_sparrow", "diffuse_reflectance": 0.0,
                 "specular_reflectance": 1.0, "eta": 1e30}, "exponent",
                [exponent_of_roughness(r) for r in roughness_nodes()])
    distribution, geometry = key.split("/")
    return ({"type": "cook_torrance", "k": 0.0, "specular_reflectance": 1.0, "f0": 1.0,
             "distribution": distribution, "geometry": geometry}, "roughness",
            roughness_nodes())


def measure(key, strata=STRATA, n_mu=N_MU, progress=None, lanes=1 << 22):
    """1 - E at the nodes of table ``key``: a list of N_ROUGHNESS rows of ``n_mu`` values.
    Sample points are traced ``lanes`` at a time at most (memory stays bounded)."""
    d, name, values = lobe(key)
    bsdf = mi.load_dict(d)
    params = mi.traverse(bsdf)
    mus = np.asarray(mu_nodes(n_mu))
    per_node = strata * strata
    chunk = max(1, min(n_mu, lanes // per_node))
    g = (np.arange(strata) + 0.5) / strata
    gx, gy = (a.ravel() for a in np.meshgrid(g, g, indexing="ij"))
    batches = []
    for start in range(0, n_mu, chunk):
        mu = np.repeat(mus[start:start + chunk], per_node)
        k = len(mu) // per_node
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = mi.Vector3f(mi.Float(np.sqrt(1 - mu * mu)), 0, mi.Float(mu))
        u2 = mi.Point2f(mi.Float(np.tile(gx, k)), mi.Float(np.tile(gy, k)))
        batches.append((k, si, dr.full(mi.Float, 0.5, len(mu)), u2))
    rows = []
    for v in values:
        params[f"{name}.value"] = v
        params.update()
        row = []
        for k, si, u1, u2 in batches:
            _, weight = bsdf.sample(mi.BSDFContext(), si, u1, u2)
            w = np.array(weight[0], dtype=np.float64).reshape(k, per_node)
            row += [float(1 - e) for e in w.mean(axis=1)]
        rows.append(row)
        if progress is not None:
            progress(1)
    return rows


def build(strata=STRATA, keys=None, progress=None):
    """Every table (or ``keys``) as the JSON-ready dict ``core.energy`` reads."""
    tables = {}
    for key in keys or table_keys():
        loss = measure(key, strata, progress=progress)
        # E above 1 (the V-groove G with GGX's D at grazing incidence, by up to 0.2%):
        # nothing to give back there
        loss = [[round(max(x, 0.0), 7) for x in row] for row in loss]
        tables[key] = {"one_minus_e": loss,
                       "one_minus_e_avg": [round(one_minus_average(row), 8) for row in loss]}
    return {
        "format": 1,
        "what": "1 - E(mu, r) of white single-scattering microfacet lobes (F = 1), rows "
                "r = j / (n - 1), columns mu = i / (n - 1) (the first measured at mu_first), "
                "and 1 - E_avg(r); see mitsuba_brdfs/core/energy.py",
        "n_mu": N_MU, "n_roughness": N_ROUGHNESS, "mu_first": mu_nodes()[0],
        "samples_per_node": strata * strata,
        "made": datetime.date.today().isoformat(),
        "mitsuba": mi.__version__, "drjit": dr.__version__,
        "tables": tables,
    }
