"""Measured materials as parameter sets: the Ngan et al. 2005 fits to the MERL BRDFs.

References: A. Ngan, F. Durand, W. Matusik, "Experimental Analysis of BRDF Models", EGSR
2005; W. Matusik et al., "A Data-Driven Reflectance Model", SIGGRAPH 2003 (the MERL
measurements); the fitted parameters as the BRDF benchmark publishes them
(https://github.com/bsdfbenchmark/bbm, ``fits/ngan_*.fit``, BSD 3-clause; the source and
licence are in the header of ``ngan2005.csv``, written by ``scripts/make_ngan2005.py``).

``ngan2005(model, material)`` returns a dict for ``mi.load_dict``. Each fit is a Lambertian
d / pi (d = the fit's diffuse albedo, MERL's RGB) plus a lobe (BBM's formulas, without the
cosine that ``eval`` adds), mapped exactly onto the plugins:

==================  =============================================  ==========================
``model``           the fitted lobe (a = the lobe's rgb albedo)    preset
==================  =============================================  ==========================
ashikhmin_shirley   a (n+1)/(8 pi) (n.h)^n F(h.i) /                ``ashikhmin_shirley``:
                    ((h.i) max(n.i, n.o)), F Schlick, F0            Rs = F0, specular_scale = a,
                                                                   nu = nv = n, diffuse_term
                                                                   = lambert, Rd = d
blinn_phong         a (n+2)/(2 pi) (n.h)^n (half vector, see       ``blinn_phong`` normalized
                    below)                                         (exact): ks = a (n+2) /
                                                                   (2 pi N(n)), p = n, kd = d
cook_torrance       a D G F / (pi (n.i)(n.o)), D normalised        ``cook_torrance``: k = 1/2,
                    Beckmann of m, G V-groove, F Schlick with      m_D = 2 d, m_S = a, f0 = eta,
                    F0 = eta                                       roughness = m,
                                                                   specular_scale = 8 / pi
ward                a exp(-tan^2 / m^2) / (4 pi m^2 sqrt(ci co))   ``ward`` form ward,
                                                                   rho_s = a, alpha = m, rho_d = d
ward_duer           a exp(-tan^2 / m^2) / (4 pi m^2 ci co)         ``ward`` form duer, as above
==================  =============================================  ==========================

Blinn-Phong: BBM evaluates ``NganBlinnPhong`` as a Phong lobe around the mirror direction,
a (n+2)/(2 pi) cos^n(alpha_r). Read that way, the fits' specular albedo at normal incidence
is a median 0.33 of the mean of the other four fits of the same material, and their
exponents are a median 1.47 times the Ashikhmin-Shirley (half-vector) exponent of the same
material (1.31 times Ward's, as n = 2 / m^2 - 2): a mirror lobe as wide as those would need a
quarter of the exponent. Read as a half-vector lobe a (n+2)/(2 pi) (n.h)^n, the same
parameters give a median 1.27 of the others' albedo (within their spread: Ward 1.34,
Ashikhmin-Shirley 0.80) at the widths the exponents match. The presets take the half-vector
reading (the one the paper names); ``scripts/ngan2005_blinn_phong.py`` measures it.

Albedo: every preset reflects at most 1 up to 85 deg of incidence (tested). At grazing
incidence Ward-Duer's normalisation (1 / cos theta) does not bound it: 49 of its presets
exceed 1 at 89.9 deg; the original Ward's (1 / sqrt(cos theta)) does not bound it either
in general, but its presets stay below 1 (see docs/presets.md).
"""
import csv
import functools
import math
import pathlib

from ..bsdf_xml import XML_VERSION, dict_to_xml

__all__ = ["MODELS", "XML_VERSION", "names", "ngan2005", "raw", "suggest", "to_xml"]

#: the five fitted models, in the order of the paper
MODELS = ("ashikhmin_shirley", "blinn_phong", "cook_torrance", "ward", "ward_duer")

_DATA = pathlib.Path(__file__).with_name("ngan2005.csv")


@functools.lru_cache(maxsize=1)
def _table():
    """{(material, model): row} of ngan2005.csv."""
    with open(_DATA, newline="") as f:
        lines = (line for line in f if not line.startswith("#"))
        return {(r["material"], r["model"]): r for r in csv.DictReader(lines)}


def names():
    """The 86 MERL material names of the fits, sorted."""
    return sorted({m for m, _ in _table()})


def suggest(word, choices):
    """' (did you mean ...?)' with the closest of ``choices``, or '' (``messages.suggest``,
    looser: material names are long)."""
    from ..messages import suggest as closest
    return closest(word, choices, cutoff=0.4)


def _check(model, material):
    if model not in MODELS:
        raise ValueError(f"presets: unknown model '{model}'{suggest(model, MODELS)}; "
                         f"models: {', '.join(MODELS)}")
    if (material, model) not in _table():
        raise ValueError(f"presets: unknown material '{material}'{suggest(material, names())}"
                         f"; 'presets list' names all {len(names())}")


def raw(model, material):
    """BBM's parameters of one fit: {'diffuse': (r, g, b), 'albedo': (r, g, b), and
    'fresnel', 'sharpness' or 'roughness' as the model has them}."""
    _check(model, material)
    r = _table()[(material, model)]
    out = {"diffuse": tuple(float(r[f"diffuse_{c}"]) for c in "rgb"),
           "albedo": tuple(float(r[f"albedo_{c}"]) for c in "rgb")}
    out.update({k: float(r[k]) for k in ("fresnel", "sharpness", "roughness") if r[k]})
    return out


def _rgb(values, scale=1.0):
    return {"type": "rgb", "value": [float(v) * scale for v in values]}


def blinn_phong_ks(a, n):
    """ks of ``blinn_phong`` (normalized, exact N(n)) equal to a (n+2) / (2 pi) (n.h)^n."""
    return a * 4 * (n + 2.0 ** (-0.5 * n)) / (n + 4)


def ngan2005(model, material):
    """The fit of ``model`` (one of ``MODELS``) to the MERL ``material`` (one of ``names()``)
    as a dict for ``mi.load_dict`` (see the module docstring for the mapping)."""
    p = raw(model, material)
    d, a = p["diffuse"], p["albedo"]
    if model == "ashikhmin_shirley":
        n = p["sharpness"]
        return {"type": "ashikhmin_shirley", "diffuse_term": "lambert",
                "diffuse_reflectance": _rgb(d), "specular_reflectance": p["fresnel"],
                "specular_scale": _rgb(a), "nu": n, "nv": n}
    if model == "blinn_phong":
        n = p["sharpness"]
        return {"type": "blinn_phong", "form": "normalized", "normalization": "exact",
                "diffuse_reflectance": _rgb(d),
                "specular_reflectance": _rgb([blinn_phong_ks(x, n) for x in a]), "exponent": n}
    if model == "cook_torrance":
        return {"type": "cook_torrance", "distribution": "beckmann",
                "geometry": "cook_torrance", "k": 0.5, "diffuse_reflectance": _rgb(d, 2.0),
                "specular_reflectance": _rgb(a), "f0": p["fresnel"],
                "roughness": p["roughness"], "specular_scale": 8 / math.pi}
    form = "ward" if model == "ward" else "duer"
    return {"type": "ward", "form": form, "diffuse_reflectance": _rgb(d),
            "specular_reflectance": _rgb(a), "alpha_u": p["roughness"],
            "alpha_v": p["roughness"]}


def to_xml(preset, version=False):
    """A preset dict as a Mitsuba ``<bsdf>`` element (``bsdf_xml``); ``version``: with the
    attribute ``version="3.0.0"`` that Mitsuba needs on a file's root element
    (``mi.load_file``, ``check``, ``<include filename="..."/>`` inside a ``<shape>``) and
    refuses on an element nested in a scene."""
    return dict_to_xml(preset, version=version)
