"""Helpers and checkers shared by the per-model test files.

A checker asserts one property of a BSDF; what differs between the models (the plugin, the
tolerances, the reference lobes) comes in as arguments, so that the test calling it still
says what it checks. Directions are local-frame unit vectors, numpy arrays of shape (N, 3).
The checks a command line can share (sampling, energy, reciprocity, stability) are in
``mitsuba_brdfs.validate`` and imported from there; what is here serves the tests alone.
At the end, the grid scenes of ``test_scenes*.py`` (many spheres in one render).

The generic tests (every model of the package) take their settings from what each model
module declares (``FACTS``, ``mitsuba_brdfs.core.facts``): ``FACTS`` here maps every plugin
to its declaration, and ``check_declared`` fails naming the module and what it must add.
"""
import gc
import math
import sys

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from mitsuba.chi2 import ChiSquareTest, SphericalDomain

from mitsuba_brdfs.models import facts, module_of
from mitsuba_brdfs.validate.directions import random_upper, sph  # noqa: F401
from mitsuba_brdfs.validate.probe import (  # noqa: F401
    floats, interaction, point2, sample_bsdf, to_np, vec)
from mitsuba_brdfs.validate import directions as _directions
from mitsuba_brdfs.validate.directions import (  # noqa: F401
    diffuse_eval_pairs, eval_pairs, hard_pairs, midpoint_hemisphere, mirror_pairs, random_pairs,
    unit, unit_f32)
from mitsuba_brdfs.validate.energy import (  # noqa: F401
    albedo, albedo_at, check_albedo_at_most_one, check_albedo_is_one)
from mitsuba_brdfs.validate.probe import context, eval_np, load_bsdf, pdf_np  # noqa: F401
from mitsuba_brdfs.validate.reciprocity import check_reciprocal, eval_both_ways  # noqa: F401
from mitsuba_brdfs.validate.sampling import (  # noqa: F401
    check_chi2, check_sample_weight_is_eval_over_pdf)
from mitsuba_brdfs.validate.stability import (  # noqa: F401
    CORNERS, CORNERS_FINE, check_eval_pdf_finite, check_finite_gradients, check_samples_finite,
    check_zero_below_horizon, corner_samples)

F = mi.BSDFFlags


# -- what the models declare ---------------------------------------------------------------------

#: plugin name -> its ``Facts``, for every model of the package (``mitsuba_brdfs.models.facts``)
FACTS = facts()


def check_declared(plugin, *fields):
    """The model's module declares each of ``fields`` in its ``FACTS`` (not empty)."""
    missing = [f for f in fields if not getattr(FACTS[plugin], f)]
    assert not missing, (f"{module_of(plugin)}: the FACTS of {plugin!r} declare no "
                         f"{', '.join(missing)} (see mitsuba_brdfs/core/facts.py)")


# -- directions ----------------------------------------------------------------------------------

def traced_code(d):
    """Code objects run while tracing eval, pdf, eval_pdf and sample of the BSDF ``d`` (a
    load_dict dict) on a few directions: what an option makes a scene trace."""
    bsdf = mi.load_dict(d)
    rng = np.random.default_rng(1)
    wi = rng.normal(size=(16, 3))
    wi[:, 2] = np.abs(wi[:, 2]) + 0.1
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    si, wo, ctx = interaction(wi), vec(wi * [-1, -1, 1]), mi.BSDFContext()
    seen = set()

    def profile(frame, event, arg):
        if event == "call":
            seen.add(frame.f_code)

    sys.setprofile(profile)
    try:
        out = [bsdf.eval(ctx, si, wo), bsdf.pdf(ctx, si, wo), *bsdf.eval_pdf(ctx, si, wo)]
        bs, w = bsdf.sample(ctx, si, floats(np.linspace(0, 1, 16)),
                            point2(np.linspace(0.1, 0.9, 16), np.linspace(0.9, 0.1, 16)))
    finally:
        sys.setprofile(None)
    dr.eval(out, bs.wo, bs.pdf, w)
    return seen


def codes(*functions):
    """The code objects of ``functions``."""
    return {f.__code__ for f in functions}


def hard_directions():
    """The hard directions of the tests: ``check``'s (``validate.directions``: the normal,
    grazing at cos = 1e-7, on the horizon, mirror pairs, below the surface), grazing along -v
    too, and the normal tilted by 1e-7 and 1e-20, where a direction's tangent projection
    vanishes (Oren-Nayar's G, a half vector's azimuth)."""
    eps = 1e-7
    g = np.sqrt(1 - eps * eps)
    more = np.array([[0, -g, eps], [0, 1e-7, 1], [1e-7, 0, 1], [1e-20, 1e-20, 1]])
    return np.concatenate([_directions.hard_directions(), unit(more)])


def warp_chi2(warp, pdf, ires, res=121):
    """Mitsuba's chi-square test of a warp of the unit square onto the sphere: the
    directions ``warp(u)`` (``u`` a ``Point2f`` of uniform samples) against the density
    ``pdf(w)``; ``res`` and ``ires`` are the test's histogram and integration resolutions.
    Returns (whether the density fits, the test's messages)."""
    test = ChiSquareTest(domain=SphericalDomain(), sample_func=lambda s: warp(mi.Point2f(s[0], s[1])),
                         pdf_func=pdf, sample_dim=2, res=res, ires=ires)
    return test.run(quiet=True), test.messages


def check_derivative_matches_float64(bsdf, key, x, reference, rtol, atol, n=64, seed=4,
                                     h=1e-5):
    """d eval / d ``key`` (a traverse key of ``bsdf``, now at ``x``) by forward-mode AD at
    ``n`` random pairs equals the central difference of ``reference(wi, wo, value)`` (float64,
    f cos, at the float32 directions the plugin sees); ``atol`` a function of the
    difference. Returns the difference."""
    rng = np.random.default_rng(seed)
    wi, wo = random_upper(rng, n), random_upper(rng, n)
    params = mi.traverse(bsdf)
    dr.enable_grad(params[key])
    params.update()
    f = bsdf.eval(mi.BSDFContext(), interaction(wi), vec(wo))
    dr.forward(params[key])
    g = to_np(dr.grad(f))[:, 0]
    wi32, wo32 = unit_f32(wi), unit_f32(wo)
    fd = (reference(wi32, wo32, x + h) - reference(wi32, wo32, x - h))[:, 0] / (2 * h)
    np.testing.assert_allclose(g, fd, rtol=rtol, atol=atol(fd))
    return fd


# -- textures ------------------------------------------------------------------------------------

def bitmap(filename):
    """A bitmap texture of raw values, looked up without filtering."""
    return {"type": "bitmap", "filename": str(filename), "raw": True, "filter_type": "nearest"}


def write_bitmap(path, value, res=4):
    """A constant res x res image of value (a scalar or a colour); returns its file name."""
    arr = np.full((res, res, np.size(value)), value, dtype=np.float32)
    mi.Bitmap(arr).write(str(path))
    return str(path)


def write_halves(path, left, right):
    """A 2x2 image, `left` where u < 0.5 and `right` where u >= 0.5; returns its texture."""
    arr = np.zeros((2, 2, np.size(left)), np.float32)
    arr[:, 0], arr[:, 1] = left, right
    mi.Bitmap(arr).write(str(path))
    return bitmap(path)


def eval_left_right(bsdf, wi, wo):
    """eval at one pair of directions on the left (u = 0.25) and the right (u = 0.75) half
    of the uv square: shape (2, C)."""
    si = interaction(np.repeat(np.reshape(wi, (1, 3)), 2, axis=0))
    si.uv = mi.Point2f([0.25, 0.75], [0.5, 0.5])
    return to_np(bsdf.eval(mi.BSDFContext(), si, vec(np.repeat(np.reshape(wo, (1, 3)), 2, axis=0))))


def check_textured_equals_constant(textured, const):
    """A BSDF whose parameters are constant bitmaps is spatially varying and evaluates (eval
    and pdf) like the same BSDF with the constants."""
    assert textured.flags() & F.SpatiallyVarying
    assert not const.flags() & F.SpatiallyVarying
    wi, wo = random_pairs(11, 1000)
    np.testing.assert_allclose(eval_np(textured, wi, wo), eval_np(const, wi, wo), rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(pdf_np(textured, wi, wo), pdf_np(const, wi, wo), rtol=1e-5, atol=1e-7)


def check_refused(plugin, params, msg):
    """Loading the plugin with params raises a RuntimeError whose message matches msg."""
    with pytest.raises(RuntimeError, match=msg):
        mi.load_dict({"type": plugin, **params})


def load_xml(plugin, body):
    """The plugin from a scene-file description, with body (its parameter elements)."""
    return mi.load_string(f'<bsdf version="3.0.0" type="{plugin}">{body}</bsdf>')


def check_xml_refused(plugin, body, msg):
    """Loading the plugin from a scene file with body raises a RuntimeError matching msg."""
    with pytest.raises(RuntimeError, match=msg):
        load_xml(plugin, body)


# -- highlights --------------------------------------------------------------------------------

def half_width_at_normal_incidence(bsdf, phi=0.0):
    """Angle (degrees) from the normal at which f = eval / cos(theta_o) falls to half its
    peak, with the light along n, in the plane of azimuth phi: the highlight's width."""
    d = np.radians(np.linspace(0, 40, 40001))
    wo = sph(d, phi)
    f = eval_np(bsdf, np.repeat([[0.0, 0.0, 1.0]], len(d), axis=0), wo)[:, 0] / wo[:, 2]
    below = f < 0.5 * f[0]
    assert below.any(), "the lobe is wider than 40 degrees"
    return np.degrees(d[np.argmax(below)])


def roughconductor_half_width(alpha, phi=0.0, alpha_v=None):
    """half_width_at_normal_incidence of Mitsuba's Beckmann roughconductor (Fresnel 1)."""
    rc = mi.load_dict({"type": "roughconductor", "distribution": "beckmann", "material": "none",
                       "alpha_u": alpha, "alpha_v": alpha if alpha_v is None else alpha_v})
    return half_width_at_normal_incidence(rc, phi)



# -- eval --------------------------------------------------------------------------------------

def check_eval(bsdf, wi, wo, want, rtol=5e-4, ctx=None):
    """eval(wi, wo) = want (with the cosine) to rtol, and to 1e-6 of the largest value."""
    np.testing.assert_allclose(eval_np(bsdf, wi, wo, ctx), want, rtol=rtol, atol=1e-6 * want.max())


# -- lobes and contexts --------------------------------------------------------------------------

def check_glossy_and_diffuse_lobes(bsdf, glossy=F.GlossyReflection | F.FrontSide):
    """Two lobes: component 0 with the flags `glossy`, component 1 a diffuse reflection."""
    assert bsdf.component_count() == 2
    assert bsdf.flags(0) == glossy
    assert bsdf.flags(1) == F.DiffuseReflection | F.FrontSide
    assert bsdf.flags() == bsdf.flags(0) | bsdf.flags(1)


def check_context_selects_lobes(bsdf, wi, wo, spec, diff, rtol, atol, lobe_pdf=False):
    """A BSDF with a glossy lobe (component 0) and a diffuse one (component 1). A context that
    selects one lobe, by index or by type, evaluates to that lobe alone (spec or diff, without
    the cosine, at the pairs wi, wo; atol is a number or a function of those values) and
    samples only that lobe (the diffuse one with the cosine pdf); one that selects nothing
    evaluates and samples to zero. With lobe_pdf, a sample's pdf is also the selected lobe's
    own pdf (pdf and eval_pdf with the context), and nothing selected has pdf zero."""
    cases = {
        "component0": (dict(component=0), spec),
        "component1": (dict(component=1), diff),
        "glossy_mask": (dict(type_mask=+F.Glossy), spec),
        "diffuse_mask": (dict(type_mask=+F.Diffuse), diff),
        "nothing": (dict(type_mask=+F.Transmission), 0 * spec),
    }
    for name, (attrs, want) in cases.items():
        ctx = context(**attrs)
        tol = atol(want) if callable(atol) else atol
        np.testing.assert_allclose(eval_np(bsdf, wi, wo, ctx), want * wo[:, 2:3], rtol=rtol,
                                   atol=tol, err_msg=name)
        si, (bs, weight) = sample_bsdf(bsdf, wi[7], 5000, ctx=ctx)
        bpdf = to_np(bs.pdf)
        if name == "nothing":
            assert (to_np(weight) == 0).all() and (bpdf == 0).all()
            if lobe_pdf:
                assert (pdf_np(bsdf, wi, wo, ctx) == 0).all()
            continue
        # a single-lobe context returns the lobe's type broadcast (width 1)
        t = np.broadcast_to(to_np(bs.sampled_type), (5000,))[bpdf > 0]
        glossy = name in ("component0", "glossy_mask")
        assert (t == +bsdf.flags(0 if glossy else 1)).all(), name
        if lobe_pdf:
            _, pdf_ctx = bsdf.eval_pdf(ctx, si, bs.wo)
            np.testing.assert_allclose(bpdf, to_np(pdf_ctx), rtol=1e-6, err_msg=name)
            np.testing.assert_allclose(bpdf, to_np(bsdf.pdf(ctx, si, bs.wo)), rtol=1e-6, err_msg=name)
        if not glossy:
            np.testing.assert_allclose(bpdf[bpdf > 0], to_np(bs.wo)[bpdf > 0, 2] / np.pi, rtol=1e-5)


def check_diffuse_context(bsdf, wi, wo, want, cases, rtol, atol):
    """A BSDF with one diffuse lobe, for each (context attributes, selected) of cases: if
    selected, eval is want (with the cosine), the pdf is positive and every sample is a
    diffuse reflection with a positive weight; if not, eval, pdf and weights are zero."""
    for attrs, on in cases:
        ctx = context(**attrs)
        np.testing.assert_allclose(eval_np(bsdf, wi, wo, ctx), want if on else 0 * want, rtol=rtol,
                                   atol=atol, err_msg=str(attrs))
        assert (pdf_np(bsdf, wi, wo, ctx) > 0).all() == on, attrs
        _, (bs, w) = sample_bsdf(bsdf, wi[3], 1000, ctx=ctx)
        assert ((to_np(w) > 0).all() if on else (to_np(w) == 0).all()), attrs
        if on:
            t = np.broadcast_to(to_np(bs.sampled_type), (1000,))
            assert (t == +(F.DiffuseReflection | F.FrontSide)).all(), attrs


# -- parameters through mi.traverse ------------------------------------------------------------

def param_key(params, suffix):
    """The first key of params that ends with suffix."""
    return next(k for k in params.keys() if k.endswith(suffix))


def check_update_changes_render(scene, params, key, value, msg=None):
    """Setting params[key] to value changes the rendered image (same seed)."""
    img0 = np.array(mi.render(scene, spp=4, seed=0))
    params[key] = value
    params.update()
    img1 = np.array(mi.render(scene, spp=4, seed=0))
    assert np.abs(img0 - img1).max() > 1e-3, msg


def working_lobes(bsdf):
    """How many of the BSDF's components do any work: evaluated alone (``ctx.component``),
    a component is non-zero for some pair of directions."""
    wi, wo = mirror_pairs(300, 3, mirrors=20)
    return sum(bool((eval_np(bsdf, wi, wo, context(component=i)) > 0).any())
               for i in range(bsdf.component_count()))


def check_update_changes_lobes(scene, params, key, value, before, after):
    """The sphere's BSDF has `before` working lobes, and `after` once params[key] is set to
    value; its components (which wrappers copy) stay the same."""
    bsdf = scene.shapes()[0].bsdf()
    flags = [bsdf.flags(i) for i in range(bsdf.component_count())]
    assert working_lobes(bsdf) == before
    params[key] = value
    params.update()
    assert working_lobes(bsdf) == after
    assert [bsdf.flags(i) for i in range(bsdf.component_count())] == flags


def check_updates_reuse_kernel(scene, suffix, values):
    """Rendering after setting the parameter ending with suffix to each of values runs only
    kernels the render before the updates ran (compared by the hash of their IR: a value
    baked in as a literal changes it; whether Dr.Jit finds them in its cache is not
    asserted). The first ``update()`` after a load may lay out the call data anew, once,
    whatever the value: the check starts after one."""
    params = mi.traverse(scene)
    key = param_key(params, suffix)
    params.set_dirty(key)
    params.update()

    def jit_hashes():
        return {h["hash"] for h in dr.kernel_history() if h["type"] == dr.KernelType.JIT}

    with dr.scoped_set_flag(dr.JitFlag.KernelHistory, True):
        dr.kernel_history()  # clear
        dr.eval(mi.render(scene, spp=2))
        before, after = jit_hashes(), set()
        for v in values:
            params[key] = v
            params.update()
            dr.eval(mi.render(scene, spp=2))
            after |= jit_hashes()
    assert before and after and after <= before, (suffix, after - before)


# -- renders -----------------------------------------------------------------------------------

#: the light of ``small_scene``: a point light up and to the right of the camera
POINT_LIGHT = {"type": "point", "position": [2, 2, 4], "intensity": {"type": "rgb", "value": 30}}


def camera(res=24, spp=4, fov=30):
    """A perspective camera on the z axis, 5 from the origin and looking at it: a res x res
    film (box filter, the variant's own pixel format), ``spp`` independent samples."""
    return {"type": "perspective", "fov": fov,
            "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": res, "height": res,
                     "pixel_format": "luminance" if mi.is_monochromatic else "rgb",
                     "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": spp}}


def small_scene(bsdf, res=24, integrator="path", max_depth=3, spp=4, light=POINT_LIGHT, env=0.2,
                shared=False):
    """A unit sphere ``ball`` lit by a point light and a dim environment, seen by ``camera``.

    ``integrator``: a name (``path`` with ``max_depth``) or an integrator dict; ``light``: an
    emitter dict, or None; ``env``: the constant environment's radiance, or None; ``shared``:
    the BSDF is declared at the top level as ``mat`` (traverse keys ``mat.<name>``) and the
    sphere refers to it, instead of nesting it (``ball.bsdf.<name>``).
    """
    if isinstance(integrator, str):
        integrator = {"type": integrator, **({"max_depth": max_depth} if integrator == "path" else {})}
    scene = {"type": "scene", "integrator": integrator, "sensor": camera(res, spp)}
    if shared:
        scene["mat"] = bsdf
        bsdf = {"type": "ref", "id": "mat"}
    scene["ball"] = {"type": "sphere", "bsdf": bsdf}
    if light is not None:
        scene["light"] = light
    if env is not None:
        scene["env"] = {"type": "constant", "radiance": {"type": "rgb", "value": env}}
    return mi.load_dict(scene)


def check_render(bsdf, integrator="path", res=24, spp=4, lit=True, msg=None):
    """The sphere scene with bsdf (a dict) renders to finite values, and, if lit, not to
    black (mean > 1e-3)."""
    img = np.array(mi.render(small_scene(bsdf, res=res, integrator=integrator), spp=spp))
    assert np.isfinite(img).all(), msg
    if lit:
        assert img.mean() > 1e-3, msg


def check_prb_gradients(scene, suffixes, nonzero=True):
    """The scene renders with the prb integrator; the gradients of the mean pixel w.r.t. the
    parameters ending with suffixes are finite (and, with nonzero, not all zero)."""
    params = mi.traverse(scene)
    keys = [param_key(params, s) for s in suffixes]
    dr.enable_grad(*(params[k] for k in keys))
    params.update()
    img = mi.render(scene, params, spp=4)
    dr.backward(dr.mean(img, axis=None))
    for key in keys:
        g = np.array(dr.grad(params[key]))
        assert np.isfinite(g).all(), key
        if nonzero:
            assert np.abs(g).max() > 0, key


def check_spectral_eval_and_render(variant, bsdf, wi=(0, 0, 1), wo=(0.6, 0, 0.8), scene_bsdf=None):
    """In a spectral variant, bsdf (a dict) evaluates to finite positive values at four
    wavelengths and, in an llvm variant, the sphere with scene_bsdf (by default the plugin
    with its defaults) renders, not black."""
    mi.set_variant(variant)
    b = mi.load_dict(bsdf)
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(*wi)
    si.wavelengths = mi.Spectrum(450, 500, 600, 650)
    v = np.array(b.eval(mi.BSDFContext(), si, mi.Vector3f(*wo)))
    assert np.isfinite(v).all() and (v > 0).all()
    if variant.startswith("llvm"):
        check_render(scene_bsdf or {"type": bsdf["type"]}, res=8, spp=2)


# -- grid scenes: many spheres in one render (test_scenes*.py) -----------------------------------
# A test file using them takes the fixture: ``pytestmark = pytest.mark.usefixtures(
# "one_scene_at_a_time")``, with ``one_scene_at_a_time`` imported from here.

T = mi.ScalarTransform4f

#: pixels per grid cell, samples per pixel, seed, distance between sphere centres
CELL, SPP, SEED, SPACING = 16, 4, 7, 2.5
POINT = {"type": "point", "position": [3, 4, 12], "intensity": {"type": "rgb", "value": 200}}
SPOT = {"type": "spot", "to_world": T().look_at(origin=[3, 4, 12], target=[0, 0, 0], up=[0, 1, 0]),
        "cutoff_angle": 30, "intensity": {"type": "rgb", "value": 200}}
DIRECTIONAL = {"type": "directional", "direction": [-0.3, -0.4, -1],
               "irradiance": {"type": "rgb", "value": 1.5}}


def grid(names, cols):
    """(cols, rows) of a grid holding ``names``, and each name's (column, row)."""
    rows = math.ceil(len(names) / cols)
    return cols, rows, {n: (i % cols, i // cols) for i, n in enumerate(names)}


#: distance of the camera to the grid
DIST = 40.0


def fov(cols):
    """The horizontal field of view that shows ``cols`` cells of the grid."""
    return 2 * math.degrees(math.atan(cols * SPACING / 2 / DIST))


def grid_scene(cells, cols=3, integrator=None, light=POINT, env=0.2, optimize=True,
               shapes=None):
    """A scene with one sphere per entry of ``cells`` (name -> BSDF dict), on a grid of
    ``cols`` columns facing the camera; each sphere fills one CELL x CELL block.
    ``shapes`` (name -> shape dict without position) replaces the spheres' shapes."""
    names = list(cells)
    cols, rows, where = grid(names, cols)
    scene = {
        "type": "scene",
        "integrator": integrator or {"type": "path", "max_depth": 3},
        "sensor": {"type": "perspective", "fov": fov(cols), "fov_axis": "x",
                   "to_world": T().look_at(origin=[0, 0, DIST], target=[0, 0, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": cols * CELL, "height": rows * CELL,
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": SPP}},
        "light": light,
    }
    if env:
        scene["env"] = {"type": "constant", "radiance": {"type": "rgb", "value": env}}
    for name, bsdf in cells.items():
        c, r = where[name]
        centre = [(c + 0.5 - cols / 2) * SPACING, (rows / 2 - r - 0.5) * SPACING, 0]
        shape = dict((shapes or {}).get(name, {"type": "sphere", "radius": 1.0}))
        shape["to_world"] = T().translate(centre) @ shape.get("to_world", T())
        scene[name] = {**shape, "bsdf": bsdf}
    return mi.load_dict(scene, optimize=optimize)


def blocks(img, names, cols=3):
    """name -> the block of pixels of the sphere ``name`` in a grid_scene render."""
    img = np.asarray(img, dtype=np.float64)
    _, _, where = grid(list(names), cols)
    return {n: img[r * CELL:(r + 1) * CELL, c * CELL:(c + 1) * CELL] for n, (c, r) in where.items()}


def render(scene, params=None, spp=SPP, seed=SEED, **kw):
    return np.array(mi.render(scene, params, spp=spp, seed=seed, **kw), dtype=np.float64)


def rendered(cells, spp=SPP, seed=SEED, **kw):
    """The image of ``grid_scene(cells, **kw)``, the scene dropped before returning."""
    scene = grid_scene(cells, **kw)
    img = render(scene, spp=spp, seed=seed)
    del scene
    gc.collect()
    return img


@pytest.fixture(autouse=True)
def one_scene_at_a_time():
    """A render traces the methods of every live BSDF: the scenes of earlier tests must be
    gone (kernel sizes are measured, and compiling less is faster). Tests that hold
    several scenes drop each (``del``, then a collection) before the next renders."""
    gc.collect()
    yield
    gc.collect()


def merl_file(path, spec, dims, position="centre"):
    """Write a MERL file of the BRDF of ``spec`` (a load_dict dict) at the bins' directions
    (``merl.from_bsdf``: the centres of their cells; NaN, unmeasured, below the horizon);
    returns the values written."""
    from mitsuba_brdfs.measured import merl
    f = merl.from_bsdf(mi.load_dict(spec), dims, position)
    merl.write(path, f, dims)
    return f


def check_fit_matrix(path, source_model, name, dims, samples=None, evaluations=None,
                     models=None):
    """fit-measured across models (``measured.matrix``): every other model (of ``models``)
    fitted to a file of ``dims`` bins (at ``path``) of ``source_model``'s material ``name``,
    each verdict 'within' or 'cannot reach'. Returns {model: the judgement}."""
    from mitsuba_brdfs.measured import data, matrix
    out = matrix.write_and_judge(path, source_model, name, dims,
                                 data.SAMPLES if samples is None else samples, evaluations,
                                 models)
    for model, j in out.items():
        assert j["verdict"] in ("within", "cannot reach"), (source_model, name, model, j)
    return out
