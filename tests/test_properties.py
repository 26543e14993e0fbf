"""The property-table command measures what it claims (on a reduced set)."""
import math

import mitsuba as mi
import numpy as np

from mitsuba_brdfs import plugin_models
from mitsuba_brdfs import properties as P


def test_albedo_of_white_lambertian_lobe_is_one_and_reciprocal():
    # ashikhmin_shirley's diffuse term alone has albedo (1 - Rs) Rd (1 - (1 - cos/2)^5)
    bsdf = P._bsdf("ashikhmin_shirley", {"specular_reflectance": 0.0, "diffuse_reflectance": 1.0,
                                         "nu": 1.0, "nv": 1.0})
    a, rel_var, below = P.sample_stats(bsdf, 0.0, 1 << 16)
    assert 0 < a <= 1.01 and rel_var >= 0 and 0 <= below <= 1
    assert P.reciprocity_error(bsdf, 2000) < 1e-4


def test_half_vector_sampler_loses_samples_at_grazing():
    bsdf = P._bsdf("ashikhmin_shirley", {"specular_reflectance": 1.0, "diffuse_reflectance": 0.0,
                                         "nu": 10.0, "nv": 10.0})
    _, _, below0 = P.sample_stats(bsdf, 0.0, 1 << 14)
    _, _, below85 = P.sample_stats(bsdf, math.radians(85), 1 << 14)
    # at normal incidence only h beyond 45 deg is lost: P = cos(45)^(n+1) = 0.022
    assert abs(below0 - 0.7071 ** 11) < 0.005 and below85 > 0.1


def test_lobe_curve_peaks_near_mirror():
    bsdf = P._bsdf("ashikhmin_shirley", {"specular_reflectance": 1.0, "diffuse_reflectance": 0.0,
                                         "nu": 1000.0, "nv": 1000.0})
    to, f = P.lobe_curve(bsdf, math.radians(30))
    assert abs(math.degrees(to[np.argmax(f)]) - 30) < 3  # the mirror side is positive


def test_command_writes_table_and_plots(tmp_path):
    from mitsuba_brdfs.__main__ import main
    assert main(["properties", "--only", "ashikhmin_shirley", "--samples", "4096",
                 "--out", str(tmp_path)]) == 0
    text = (tmp_path / "properties.md").read_text()
    for label in ("ashikhmin_shirley metal n=100", "ashikhmin_shirley plastic"):
        assert label in text
    assert (tmp_path / "albedo.png").stat().st_size > 1000
    assert (tmp_path / "lobes" / "ashikhmin_shirley.png").stat().st_size > 1000


def test_configs_cover_every_model_and_form():
    seen = {(plugin, params.get("form"), params.get("distribution"), params.get("geometry"))
            for plugin, _, params in P.CONFIGS}
    for m in ("phong", "blinn_phong"):
        for form in ("original", "modified", "normalized"):
            assert (m, form, None, None) in seen
    for d in ("beckmann", "blinn", "ggx"):
        for g in ("cook_torrance", "ggx"):
            assert ("cook_torrance", None, d, g) in seen
    options = {(plugin, k, v) for plugin, _, params in P.CONFIGS for k, v in params.items()
               if isinstance(v, str)}
    for option in [("ward", "form", "duer"), ("ward", "form", "balanced"),
                   ("blinn_phong", "normalization", "approximate"),
                   ("oren_nayar", "form", "energy_preserving"), ("oren_nayar", "sampling", "cosine")]:
        assert option in options, option
    for plugin, name in [("ashikhmin_shirley", "alpha_u"), ("phong", "alpha"), ("blinn_phong", "alpha"),
                         ("oren_nayar", "a"), ("toon", "diffuse_ramp")]:
        assert any(c[0] == plugin and name in c[2] for c in P.CONFIGS), (plugin, name)
    # every model (from its FACTS.properties), 2-3 settings each where the model has
    # parameters besides its colour
    assert {c[0] for c in P.CONFIGS} == set(plugin_models())
    for plugin in plugin_models():
        bsdf = P._bsdf(plugin, {})
        has_parameters = len(mi.traverse(bsdf).keys()) > 1 or bsdf._options()
        assert sum(c[0] == plugin for c in P.CONFIGS) >= (2 if has_parameters else 1), plugin


def test_measured_albedo_matches_closed_forms():
    """The furnace numbers of the table against values known in closed form."""
    n = 1 << 17
    cases = [  # (plugin, params, incidence, exact albedo)
        ("lambert", {"reflectance": 1.0}, 60.0, 1.0),
        # normalised lobes integrate to 1 at normal incidence
        ("phong", {"form": "normalized", "exponent": 10.0, "diffuse_reflectance": 0.0,
                   "specular_reflectance": 1.0}, 0.0, 1.0),
        ("blinn_phong", {"form": "normalized", "exponent": 10.0, "diffuse_reflectance": 0.0,
                         "specular_reflectance": 1.0}, 0.0, 1.0),
        # the original Phong lobe, cos^p of the mirror angle without a cosine: at normal
        # incidence and p = 1 it integrates cos(theta) over the hemisphere, pi
        ("phong", {"form": "original", "exponent": 1.0, "diffuse_reflectance": 0.0,
                   "specular_reflectance": 1.0}, 0.0, math.pi),
        # the modified lobe keeps the cosine: the integral of cos^2 is 2 pi / 3
        ("phong", {"form": "modified", "exponent": 1.0, "diffuse_reflectance": 0.0,
                   "specular_reflectance": 1.0}, 0.0, 2 * math.pi / 3),
    ]
    for plugin, params, theta, exact in cases:
        a, _, _ = P.sample_stats(P._bsdf(plugin, params), math.radians(theta), n)
        assert abs(a - exact) < 0.01 * exact, (plugin, params, a, exact)


def test_every_config_loads():
    for plugin, label, params in P.CONFIGS:
        assert P._bsdf(plugin, params).component_count() >= 1, label
