"""Every plugin in every Mitsuba variant this machine can run.

The wheel ships scalar, LLVM and CUDA variants in RGB, mono and spectral forms, the last two
also polarized. Every CPU variant (scalar_*, llvm_*) is tested: each plugin loads, evaluates
and samples finite values equal to those of ``llvm_ad_rgb`` (the default parameters are
grey), and renders a small image. In polarized variants the plugins must be depolarizers,
as Mitsuba's own unpolarized plugins are: ``lambert`` returns the same Mueller matrix as
``diffuse``, and between crossed polarizers it renders as ``diffuse`` does. CUDA variants
run the same test where a GPU is present.
"""
import gc

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

import mitsuba_brdfs
from checks import FACTS, blocks, camera, rendered, small_scene

PLUGINS = sorted(mitsuba_brdfs.plugin_models())
CPU_VARIANTS = [v for v in mi.variants() if v.startswith(("scalar_", "llvm_"))]
CUDA_VARIANTS = [v for v in mi.variants() if v.startswith("cuda_")]
HAS_CUDA = dr.has_backend(dr.JitBackend.CUDA)

#: (wi, wo) pairs in the local frame: normal incidence, the mirror direction, off-plane,
#: near grazing, and wo below the surface
PAIRS = [((0, 0, 1), (0, 0, 1)),
         ((0.6, 0, 0.8), (-0.6, 0, 0.8)),
         ((0.3, 0.5, 0.8124), (0.7, -0.2, 0.6855)),
         ((0.995, 0, 0.0999), (-0.9, 0.1, 0.4243)),
         ((0, 0.6, 0.8), (0.3, 0, -0.954))]
SAMPLES = [(0.1, (0.2, 0.7)), (0.5, (0.5, 0.5)), (0.9, (0.95, 0.05))]
#: wavelengths of the spectral variants' interactions (nm)
WAVELENGTHS = [450.0, 520.0, 600.0, 680.0]


def _unpolarized_counterpart(variant):
    return variant.replace("_polarized", "")


def _interaction(wi):
    """An interaction with ``wi``; directions and samples enter the kernels as opaque
    values (``dr.opaque``), so that every pair runs the same compiled kernels."""
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = dr.normalize(dr.opaque(mi.Vector3f, wi))
    si.uv = mi.Point2f(0.5, 0.5)
    if mi.is_spectral:
        si.wavelengths = type(si.wavelengths)(WAVELENGTHS)
    return si


def _values(x):
    """Channels of an unpolarized value as a flat numpy array (any variant)."""
    if mi.is_polarized:
        x = mi.unpolarized_spectrum(x)
    return np.array(x, dtype=np.float64).ravel()


def _off_diagonal_of_depolarizer(x):
    """Every Mueller entry but [0][0] (all must be 0 for an unpolarized model)."""
    m = np.array(x, dtype=np.float64).reshape(4, 4, -1)
    mask = np.ones((4, 4), bool)
    mask[0, 0] = False
    return m[mask]


def _evaluate(plugin, props=None):
    """eval, pdf and sample (weight, wo, pdf) of a plugin at PAIRS / SAMPLES, in the active
    variant, as flat numpy arrays (the weight as its channels)."""
    bsdf = mi.load_dict({"type": plugin, **(props or {})})
    ctx = mi.BSDFContext()
    out = {"eval": [], "pdf": [], "weight": [], "wo": [], "spdf": [], "mueller": []}
    for wi, wo in PAIRS:
        si = _interaction(wi)
        wo = dr.normalize(dr.opaque(mi.Vector3f, wo))
        value = bsdf.eval(ctx, si, wo)
        out["eval"].append(_values(value))
        out["pdf"].append(float(np.array(bsdf.pdf(ctx, si, wo)).ravel()[0]))
        if mi.is_polarized:
            out["mueller"].append(_off_diagonal_of_depolarizer(value))
    for s1, s2 in SAMPLES:
        si = _interaction(PAIRS[2][0])
        bs, weight = bsdf.sample(ctx, si, dr.opaque(mi.Float, s1), dr.opaque(mi.Point2f, s2))
        out["weight"].append(_values(weight))
        out["wo"].append(np.array(bs.wo, dtype=np.float64).ravel())
        out["spdf"].append(float(np.array(bs.pdf).ravel()[0]))
        if mi.is_polarized:
            out["mueller"].append(_off_diagonal_of_depolarizer(weight))
    return out


def _render(variant, bsdf):
    """A small render in ``variant`` (tiny in scalar variants, where every BSDF call is a
    Python call)."""
    mi.set_variant(variant)
    res, spp = (4, 1) if variant.startswith("scalar_") else (8, 4)
    return np.array(mi.render(small_scene(bsdf, res, spp=spp), seed=1), dtype=np.float64)


#: the BSDFs rendered together in the JIT variants: every plugin at its defaults, and every
#: load-time option (``OPTIONS``, below)
GROUPS = {"defaults": [(p, None) for p in PLUGINS]}
#: (variant, group) -> {(plugin, props) key: its block of the group's grid render}
_GRIDS = {}


def _key(plugin, props):
    return repr((plugin, props))


def _group(plugin, props):
    """The group of ``GROUPS`` that renders (plugin, props)."""
    return next(g for g, members in GROUPS.items() if (plugin, props) in members)


def _image(variant, plugin, props):
    """The render of ``plugin`` with ``props`` in ``variant``: in a scalar variant a tiny
    scene of its own; in a JIT variant its sphere of one grid scene holding its whole group
    (one kernel per variant and group, not per BSDF)."""
    if variant.startswith("scalar_"):
        return _render(variant, {"type": plugin, **(props or {})})
    group = _group(plugin, props)
    if (variant, group) not in _GRIDS:
        mi.set_variant(variant)
        members = GROUPS[group]
        cells = {f"cell{i}": {"type": p, **(q or {})} for i, (p, q) in enumerate(members)}
        gc.collect()  # (a render traces every live BSDF)
        found = blocks(rendered(cells, seed=1), cells)
        _GRIDS[variant, group] = {_key(p, q): found[f"cell{i}"]
                                  for i, (p, q) in enumerate(members)}
    return _GRIDS[variant, group][_key(plugin, props)]


#: (plugin, props) -> llvm_ad_rgb's values and image, computed once for every variant
_REFERENCE = {}


def _reference(plugin, props):
    """llvm_ad_rgb's values and image of (plugin, props), grey parameters: computed for its
    whole group at its first use (one switch of variant for the group)."""
    key = _key(plugin, props)
    if key not in _REFERENCE:
        mi.set_variant("llvm_ad_rgb")
        group = _group(plugin, props)
        for p, q in GROUPS[group]:
            _REFERENCE[_key(p, q)] = _evaluate(p, q), _image("llvm_ad_rgb", p, q)
    return _REFERENCE[key]


def _check_variant(variant, plugin, props=None):
    ref, ref_img = _reference(plugin, props)

    mi.set_variant(variant)
    got = _evaluate(plugin, props)
    for key in ("eval", "pdf", "weight", "wo", "spdf"):
        for g, r in zip(got[key], ref[key]):
            assert np.all(np.isfinite(g)), (variant, plugin, key, g)
            # grey parameters: every channel (RGB, mono, each wavelength) is the RGB value
            np.testing.assert_allclose(g, np.broadcast_to(np.ravel(r)[:1], g.shape)
                                       if key in ("eval", "weight") else r,
                                       rtol=1e-5, atol=1e-7, err_msg=f"{variant} {plugin} {key}")
    assert min(float(np.min(e)) for e in got["eval"]) >= 0
    for m in got["mueller"]:
        np.testing.assert_array_equal(m, 0, err_msg=f"{variant} {plugin}: not a depolarizer")

    img = _image(variant, plugin, props)
    assert np.all(np.isfinite(img)), (variant, plugin)
    assert img.mean() > 0.01, (variant, plugin, img.mean())
    if variant.startswith("llvm_") and "spectral" not in variant:
        # mono: a grey scene renders as in RGB, pixel for pixel (same samples)
        np.testing.assert_allclose(img, np.broadcast_to(ref_img[..., :1], img.shape),
                                   rtol=1e-4, atol=1e-6)
    if mi.is_polarized:
        # a depolarizing surface under unpolarized light: as the unpolarized variant
        plain = _image(_unpolarized_counterpart(variant), plugin, props)
        np.testing.assert_allclose(img, plain, rtol=1e-4, atol=1e-6)


@pytest.mark.parametrize("plugin", PLUGINS)
@pytest.mark.parametrize("variant", CPU_VARIANTS)
def test_every_plugin_in_every_cpu_variant(variant, plugin):
    _check_variant(variant, plugin)


#: load-time choices that trace other code than the defaults (and a texture): every
#: model's ``FACTS.traced_options``
OPTIONS = [(p, props) for p in PLUGINS for props in FACTS[p].traced_options]
GROUPS["options"] = OPTIONS


@pytest.mark.parametrize("plugin, props", OPTIONS,
                         ids=[f"{p}-{i}" for i, (p, _) in enumerate(OPTIONS)])
@pytest.mark.parametrize("variant", ["scalar_rgb", "scalar_spectral_polarized",
                                     "llvm_ad_mono_polarized"])
def test_load_time_options_in_other_variants(variant, plugin, props):
    _check_variant(variant, plugin, props)


@pytest.mark.skipif(not HAS_CUDA, reason="no CUDA device on this machine")
def test_every_plugin_in_every_cuda_variant():
    for variant in CUDA_VARIANTS:
        for plugin in PLUGINS:
            _check_variant(variant, plugin)


def test_cpu_variants_cover_the_wheel():
    """Every variant the wheel ships is tested: here, or (CUDA) where a GPU is present."""
    assert set(CPU_VARIANTS) | set(CUDA_VARIANTS) == set(mi.variants())
    assert {"scalar_rgb", "llvm_ad_rgb", "llvm_ad_mono_polarized",
            "llvm_ad_spectral_polarized"} <= set(CPU_VARIANTS)


# -- lambert against Mitsuba's diffuse, variant by variant --------------------------------------

COLOUR = {"type": "rgb", "value": [0.8, 0.3, 0.1]}


@pytest.mark.parametrize("variant", CPU_VARIANTS)
def test_lambert_equals_diffuse(variant):
    """Same spectra (upsampled, mono) or Mueller matrices, and the same render."""
    mi.set_variant(variant)
    lam = mi.load_dict({"type": "lambert", "reflectance": COLOUR})
    dif = mi.load_dict({"type": "diffuse", "reflectance": COLOUR})
    ctx = mi.BSDFContext()
    for wi, wo in PAIRS:
        si, wo = _interaction(wi), dr.normalize(dr.opaque(mi.Vector3f, wo))
        # whole values: all 16 Mueller entries in polarized variants
        np.testing.assert_allclose(np.array(lam.eval(ctx, si, wo)),
                                   np.array(dif.eval(ctx, si, wo)), rtol=1e-6, atol=1e-9)
    for s1, s2 in SAMPLES:
        si = _interaction(PAIRS[2][0])
        u1, u2 = dr.opaque(mi.Float, s1), dr.opaque(mi.Point2f, s2)
        (bs_l, w_l), (bs_d, w_d) = (b.sample(ctx, si, u1, u2) for b in (lam, dif))
        np.testing.assert_allclose(np.array(w_l), np.array(w_d), rtol=1e-6, atol=1e-9)
        np.testing.assert_allclose(np.array(bs_l.wo), np.array(bs_d.wo), rtol=1e-6, atol=1e-7)
    img_l = _render(variant, {"type": "lambert", "reflectance": COLOUR})
    img_d = _render(variant, {"type": "diffuse", "reflectance": COLOUR})
    assert img_d.mean() > 0.01
    np.testing.assert_allclose(img_l, img_d, rtol=1e-5, atol=1e-7)


# -- crossed polarizers ---------------------------------------------------------------------

def _polarizer_scene(bsdf, theta_camera, theta_light, res, spp):
    """A plane lit by a point light through one linear polarizer and seen through another.

    ``volpath`` traces shadow rays through the polarizers (null interfaces). A surface that
    keeps the light's polarization shows almost nothing when the two are crossed; a
    depolarizing one (Lambertian) forgets the light's polarizer, so it looks the same
    crossed or parallel.
    """
    T = mi.ScalarTransform4f

    def polarizer(theta):
        return {"type": "polarizer", "theta": {"type": "spectrum", "value": theta}}

    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "volpath", "max_depth": 4},
        "sensor": camera(res, spp, fov=20),
        "plane": {"type": "rectangle", "bsdf": bsdf},
        # in front of the camera, covering its view
        "camera_polarizer": {"type": "rectangle", "to_world": T().translate([0, 0, 4]).scale(0.5),
                             "bsdf": polarizer(theta_camera)},
        # between the light and the part of the plane in view, outside the camera's view
        "light_polarizer": {"type": "rectangle",
                            "to_world": T().look_at(origin=[0, 1.5, 1.5], target=[0, 3, 3],
                                                    up=[0, 1, 0]).scale(0.8),
                            "bsdf": polarizer(theta_light)},
        "light": {"type": "point", "position": [0, 3, 3],
                  "intensity": {"type": "spectrum", "value": 30}},
    })


@pytest.mark.parametrize("variant", [v for v in CPU_VARIANTS if v.endswith("_polarized")])
def test_lambert_between_crossed_polarizers_renders_as_diffuse(variant):
    mi.set_variant(variant)
    res, spp = (4, 2) if variant.startswith("scalar_") else (8, 16)
    images = {}
    for theta_light in (0, 90):
        for name in ("lambert", "diffuse"):
            scene = _polarizer_scene({"type": name}, 0, theta_light, res, spp)
            images[name, theta_light] = np.array(mi.render(scene, seed=2), dtype=np.float64)
    crossed = images["diffuse", 90]
    assert crossed.mean() > 0.01
    # a depolarizer forgets the light's polarizer: crossed and parallel give the same image
    np.testing.assert_allclose(crossed, images["diffuse", 0], rtol=1e-4, atol=1e-7)
    for theta_light in (0, 90):
        np.testing.assert_allclose(images["lambert", theta_light], images["diffuse", theta_light],
                                   rtol=1e-5, atol=1e-7)
