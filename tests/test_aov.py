"""The albedo AOV and the attribute queries of every plugin.

The ``aov`` integrator's ``albedo`` (what denoisers are fed) calls
``eval_diffuse_reflectance``: every plugin returns its diffuse colour, or the specular colour
where the diffuse one is black, never above 1 (Mitsuba's fallback, eval at the normal times
pi, returns the highlight's peak: 2.76 for the Ashikhmin-Shirley case below). The images are
rendered through the integrator, so they show that Mitsuba reaches the Python override.
``has_attribute`` / ``eval_attribute[_1|_3]`` come from Mitsuba's ``BSDF`` base, which finds
the parameter textures through the plugins' ``traverse``.
"""
import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

import mitsuba_brdfs
from checks import FACTS, check_declared, small_scene

PLUGINS = sorted(mitsuba_brdfs.plugin_models())
CPU_VARIANTS = [v for v in mi.variants() if v.startswith(("scalar_", "llvm_"))]


def rgb(*c):
    return {"type": "rgb", "value": list(c)}


#: (plugin, parameters, expected albedo): every model's ``FACTS.albedo``
CASES = [(p, props, expected) for p in PLUGINS for props, expected in FACTS[p].albedo]


def aov_scene(bsdf, res=8):
    """A sphere seen by a camera at 1 sample per pixel: each pixel is one ray, a hit (its
    albedo) or a miss (0); ``dd`` (distance) tells them apart."""
    return small_scene(bsdf, res, {"type": "aov", "aovs": "albedo:albedo,dd:depth"}, spp=1,
                       light=None, env=None)


def render_albedo(bsdf, res=8):
    """(albedo image (H, W, C), hit mask (H, W)) of the AOV scene in the active variant."""
    scene = aov_scene(bsdf, res)
    mi.render(scene, seed=3)
    layers = dict(scene.sensors()[0].film().bitmap().split())
    albedo = np.array(layers["albedo"], dtype=np.float64).reshape(res, res, -1)
    hit = np.array(layers["dd"], dtype=np.float64).reshape(res, res) > 0
    return albedo, hit


@pytest.mark.parametrize("plugin", PLUGINS)
def test_cases_cover_every_plugin(plugin):
    check_declared(plugin, "albedo")


@pytest.mark.parametrize("plugin, props, expected", CASES,
                         ids=[f"{c[0]}-{i}" for i, c in enumerate(CASES)])
def test_albedo_aov_is_the_diffuse_colour(plugin, props, expected):
    albedo, hit = render_albedo({"type": plugin, **props})
    assert hit.any() and (~hit).any()
    assert np.all(np.isfinite(albedo))
    assert albedo.min() >= 0 and albedo.max() <= 1
    np.testing.assert_allclose(albedo[hit], np.broadcast_to(expected, albedo[hit].shape),
                               rtol=1e-6, atol=1e-7)
    np.testing.assert_array_equal(albedo[~hit], 0)


def test_albedo_aov_follows_a_texture_per_point():
    """A checkerboard diffuse colour with black squares: the albedo is the diffuse colour on
    the coloured squares and the specular colour on the black (metal) ones."""
    bsdf = {"type": "ashikhmin_shirley", "specular_reflectance": 0.3, "nu": 50.0, "nv": 50.0,
            "diffuse_reflectance": {"type": "checkerboard", "color0": 0.0,
                                    "color1": rgb(0.6, 0.5, 0.4)}}
    albedo, hit = render_albedo(bsdf, res=16)
    got = albedo[hit]
    diffuse = np.all(np.isclose(got, [0.6, 0.5, 0.4], rtol=1e-6), axis=1)
    metal = np.all(np.isclose(got, 0.3, rtol=1e-6), axis=1)
    assert diffuse.any() and metal.any()
    assert np.all(diffuse | metal)


def test_albedo_aov_through_wrappers():
    """twosided and blendbsdf ask the nested plugin: lambert inside them gives diffuse's AOV."""
    colour = rgb(0.7, 0.5, 0.2)
    for wrap in (lambda b: {"type": "twosided", "bsdf": b},
                 lambda b: {"type": "blendbsdf", "weight": 0.25, "bsdf_0": b,
                            "bsdf_1": {"type": "diffuse", "reflectance": rgb(0.1, 0.2, 0.3)}}):
        got, hit = render_albedo(wrap({"type": "lambert", "reflectance": colour}))
        ref, _ = render_albedo(wrap({"type": "diffuse", "reflectance": colour}))
        assert hit.any()
        np.testing.assert_array_equal(got, ref)


@pytest.mark.parametrize("variant", CPU_VARIANTS)
def test_albedo_aov_equals_diffuse_in_every_variant(variant):
    """The same AOV image as Mitsuba's ``diffuse`` (spectral variants: the same wavelength
    samples, so the same noisy colours); finite, and in [0, 1] where it is not sampled by
    wavelength."""
    mi.set_variant(variant)
    colour = rgb(0.8, 0.3, 0.1)
    res = 4 if variant.startswith("scalar_") else 8
    got, hit = render_albedo({"type": "lambert", "reflectance": colour}, res)
    ref, _ = render_albedo({"type": "diffuse", "reflectance": colour}, res)
    assert hit.any()
    assert np.all(np.isfinite(got))
    np.testing.assert_allclose(got, ref, rtol=1e-6, atol=1e-7)
    if not mi.is_spectral:
        assert got.min() >= 0 and got.max() <= 1
        assert np.abs(got[hit]).max() > 0


def test_albedo_aov_of_the_highlight_case_is_not_the_peak():
    """The brief's case: the Python override, not Mitsuba's eval * pi fallback (2.76)."""
    bsdf = mi.load_dict({"type": "ashikhmin_shirley", "diffuse_reflectance": 0.4,
                         "specular_reflectance": 0.3, "nu": 20.0, "nv": 200.0})
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(0, 0, 1)
    fallback = np.array(bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(0, 0, 1))) * np.pi
    assert fallback.max() > 2  # what the AOV would show without the override
    np.testing.assert_allclose(np.array(bsdf.eval_diffuse_reflectance(si)).ravel(), 0.4, rtol=1e-6)


def test_albedo_aov_is_clipped_to_one():
    """A metal whose specular colour at normal incidence exceeds 1: cook_torrance with k = 0,
    specular_reflectance = f0 = 1 and specular_scale = 3 has the colour 3 (the scale is for
    fits whose lobe outweighs what m_S <= 1 allows). The AOV shows 1, and so does a call of
    ``eval_diffuse_reflectance``; unclipped both would be 3."""
    props = {"type": "cook_torrance", "k": 0.0, "specular_reflectance": 1.0, "f0": 1.0,
             "specular_scale": 3.0, "roughness": 0.3}
    albedo, hit = render_albedo(props)
    assert hit.any()
    np.testing.assert_allclose(albedo[hit], 1.0, rtol=1e-6)
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(0, 0, 1)
    np.testing.assert_allclose(np.array(mi.load_dict(props).eval_diffuse_reflectance(si)),
                               1.0, rtol=1e-6)
    # scaled by 0.3 the same metal's colour is 0.3, shown as it is (not a constant 1)
    albedo, _ = render_albedo({**props, "specular_scale": 0.3})
    np.testing.assert_allclose(albedo[hit], 0.3, rtol=1e-6)


# -- has_attribute / eval_attribute ------------------------------------------------------------

def _distinct_parameters(plugin):
    """The plugin loaded with defaults, then every parameter moved to its own value within
    its range through ``mi.traverse`` (colours get distinct channels): name -> value."""
    bsdf = mi.load_dict({"type": plugin})
    params = mi.traverse(bsdf)
    expected = {}
    for i, key in enumerate(k for k in params.keys() if k.endswith(".value")):
        name = key[: -len(".value")]
        value = np.array(params[key], dtype=np.float64).ravel()
        factor = 0.95 - 0.03 * i
        if value.size == 3:
            new = value * factor * np.array([1.0, 0.8, 0.6])
            params[key] = mi.Color3f(*new)
        else:
            new = value * factor
            params[key] = type(params[key])(new[0])
        expected[name] = new
    params.update()
    return bsdf, expected


@pytest.mark.parametrize("variant", ["llvm_ad_rgb", "scalar_rgb"])
@pytest.mark.parametrize("plugin", PLUGINS)
def test_attributes_are_the_parameter_textures(plugin, variant):
    mi.set_variant(variant)
    bsdf, expected = _distinct_parameters(plugin)
    assert len(expected) >= 1
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(0, 0, 1)
    for name, value in expected.items():
        assert np.all(np.array(bsdf.has_attribute(name))), name
        if value.size == 3:
            got = np.array(bsdf.eval_attribute_3(name, si), dtype=np.float64).ravel()
            np.testing.assert_allclose(got, value, rtol=1e-6, err_msg=name)
            got = np.array(bsdf.eval_attribute(name, si), dtype=np.float64).ravel()
            np.testing.assert_allclose(got, value, rtol=1e-6, err_msg=name)
        else:
            got = np.array(bsdf.eval_attribute_1(name, si), dtype=np.float64).ravel()
            np.testing.assert_allclose(got, value, rtol=1e-6, err_msg=name)
    assert not np.any(np.array(bsdf.has_attribute("no_such_parameter")))


@pytest.mark.parametrize("variant", ["llvm_ad_mono", "llvm_ad_spectral_polarized"])
def test_attributes_in_other_variants(variant):
    """Mono and (polarized) spectral values: what the parameter textures return there."""
    mi.set_variant(variant)
    colour = rgb(0.8, 0.3, 0.1)
    bsdf = mi.load_dict({"type": "ward", "diffuse_reflectance": colour, "alpha_u": 0.2})
    tex = mi.load_dict(colour)
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(0, 0, 1)
    if mi.is_spectral:
        si.wavelengths = type(si.wavelengths)([450.0, 520.0, 600.0, 680.0])
    assert np.all(np.array(bsdf.has_attribute("diffuse_reflectance")))
    np.testing.assert_allclose(np.array(bsdf.eval_attribute("diffuse_reflectance", si)),
                               np.array(tex.eval(si)), rtol=1e-6)
    np.testing.assert_allclose(np.array(bsdf.eval_attribute_1("alpha_u", si)).ravel(), 0.2,
                               rtol=1e-6)
