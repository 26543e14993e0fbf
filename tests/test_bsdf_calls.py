"""The plugins called as Mitsuba's users call a BSDF, in the style of Mitsuba's own BSDF tests.

Mitsuba's bindings convert the arguments of its C++ plugins: ``bsdf.eval(ctx, si,
wo=[0, 0, 1])``, ``bsdf.sample(ctx, si, 0.5, [0.5, 0.5])`` (lists, tuples, Python numbers,
keywords, ``active`` left out) work in every variant, and ``class_name()`` names the
model (``SmoothDiffuse``). The plugins of this package take the same arguments with the
same results as Dr.Jit values, and ``lambert`` stands in for ``diffuse`` in tests written
as Mitsuba's tests of ``diffuse``, ``twosided``, ``blendbsdf`` and ``normalmap`` are: with
Python lists for directions and samples, in ``scalar_rgb`` and in a JIT variant.
"""
import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

import mitsuba_brdfs

PLUGINS = sorted(mitsuba_brdfs.plugin_models())
#: one variant of each kind: scalar and JIT, RGB, spectral, polarized
VARIANTS = ["scalar_rgb", "llvm_ad_rgb", "scalar_spectral", "llvm_ad_spectral",
            "llvm_ad_mono_polarized"]
WAVELENGTHS = [450.0, 520.0, 600.0, 680.0]


def _si(wi):
    """An interaction as Mitsuba's tests build one: fields set from Python lists."""
    si = mi.SurfaceInteraction3f()
    si.t = 0.1
    si.p = [0, 0, 0]
    si.n = [0, 0, 1]
    si.sh_frame = mi.Frame3f(si.n)
    si.uv = [0.5, 0.5]
    si.wi = wi
    if mi.is_spectral:
        si.wavelengths = WAVELENGTHS
    return si


def _same(a, b):
    assert dr.allclose(a, b, rtol=1e-6, atol=1e-7), (a, b)


@pytest.mark.parametrize("plugin", PLUGINS)
def test_class_name_names_the_model(plugin):
    bsdf = mi.load_dict({"type": plugin})
    name = mitsuba_brdfs.plugin_models()[plugin].__name__
    assert bsdf.class_name() == name != "BSDF"
    assert str(bsdf).startswith(name + "[")


@pytest.mark.parametrize("variant", VARIANTS)
def test_every_argument_form_of_mitsubas_bindings(variant):
    """Lists, tuples, Python numbers and keywords give what Dr.Jit values give, with or
    without ``active``, for every plugin (its defaults: both lobes where it has two)."""
    mi.set_variant(variant)
    wi, wo, s1, s2 = [0.3, 0.2, 0.9327379], [-0.5, 0.1, 0.8602325], 0.4, [0.3, 0.6]
    ctx = mi.BSDFContext()
    for plugin in PLUGINS:
        bsdf = mi.load_dict({"type": plugin})
        si = _si(wi)
        v, t = mi.Vector3f(*wo), mi.Bool(True)
        f, pdf = bsdf.eval(ctx, si, v, t), bsdf.pdf(ctx, si, v, t)
        assert dr.all(f[0] > 0 if not mi.is_polarized else f[0, 0][0] > 0), (variant, plugin)
        for form in (wo, tuple(wo)):
            _same(bsdf.eval(ctx, si, form), f)
            _same(bsdf.eval(ctx, si, wo=form), f)
            _same(bsdf.eval(ctx=ctx, si=si, wo=form, active=True), f)
            _same(bsdf.pdf(ctx, si, wo=form), pdf)
            ef, ep = bsdf.eval_pdf(ctx, si, wo=form)
            _same(ef, f)
            _same(ep, pdf)
        bs, weight = bsdf.sample(ctx, si, mi.Float(s1), mi.Point2f(*s2), t)
        for a, b in ((s1, s2), (s1, tuple(s2)), (mi.Float(s1), s2)):
            for got in (bsdf.sample(ctx, si, a, b), bsdf.sample(ctx, si, sample1=a, sample2=b),
                        bsdf.sample(ctx, si, a, b, active=True)):
                _same(got[1], weight)
                _same(got[0].wo, bs.wo)
                _same(got[0].pdf, bs.pdf)
        _same(bsdf.eval_diffuse_reflectance(si), bsdf.eval_diffuse_reflectance(si, t))
        # an inactive lane gives nothing
        assert dr.all(bsdf.eval(ctx, si, wo, False) == 0, axis=None)


# -- Mitsuba's tests of diffuse and its wrappers, with lambert -------------------------------

def test_lambert_create():
    mi.set_variant("scalar_rgb")
    b = mi.load_string("<bsdf version='3.0.0' type='lambert'/>")
    assert b.component_count() == 1
    assert b.flags(0) == mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
    assert b.flags() == b.flags(0)
    assert b.class_name() == "Lambert"


@pytest.mark.parametrize("variant", ["scalar_rgb", "llvm_ad_rgb"])
def test_lambert_eval_pdf(variant):
    """eval = 0.5 cos / pi and pdf = cos / pi, with wo a Python list given by keyword."""
    mi.set_variant(variant)
    bsdf = mi.load_dict({"type": "lambert"})
    si, ctx = _si([0, 0, 1]), mi.BSDFContext()
    for theta in np.linspace(0, np.pi / 2, 12):
        wo = [float(np.sin(theta)), 0.0, float(np.cos(theta))]
        pdf, value = bsdf.pdf(ctx, si, wo=wo), bsdf.eval(ctx, si, wo=wo)[0]
        assert dr.allclose(pdf, wo[2] / dr.pi, atol=1e-7)
        assert dr.allclose(value, 0.5 * wo[2] / dr.pi, atol=1e-7)
        ef, ep = bsdf.eval_pdf(ctx, si, wo=wo)
        assert dr.allclose(ef[0], value) and dr.allclose(ep, pdf)


@pytest.mark.parametrize("variant", ["scalar_rgb", "llvm_ad_rgb"])
def test_lambert_inside_twosided(variant):
    mi.set_variant(variant)
    one = mi.load_string("<bsdf version='3.0.0' type='twosided'><bsdf type='lambert'/></bsdf>")
    assert one.component_count() == 2
    assert one.flags(1) == mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.BackSide
    si, ctx = _si([0, 0, 1]), mi.BSDFContext()
    assert dr.allclose(one.pdf(ctx, si, [0, 0, 1]), dr.inv_pi)
    assert dr.allclose(one.pdf(ctx, si, [0, 0, -1]), 0.0)

    faces = mi.load_string("""<bsdf version='3.0.0' type='twosided'>
        <bsdf type='lambert'><rgb name='reflectance' value='0.1'/></bsdf>
        <bsdf type='lambert'><rgb name='reflectance' value='0.9'/></bsdf></bsdf>""")
    n = 4
    for u in range(n):
        for v in range(n):
            si = _si(mi.warp.square_to_uniform_sphere([(u + 0.5) / n, (v + 0.5) / n]))
            up = dr.all(si.wi.z > 0)
            for x in range(n):
                for y in range(n):
                    bs, weight = faces.sample(ctx, si, 0.5, [(x + 0.5) / n, (y + 0.5) / n])
                    assert dr.allclose(weight, 0.1 if up else 0.9)
                    value, pdf = faces.eval_pdf(ctx, si, wo=bs.wo)
                    assert dr.allclose(value, weight * pdf) and dr.allclose(pdf, bs.pdf)
                    assert dr.allclose(faces.eval(ctx, si, bs.wo), value)


@pytest.mark.parametrize("variant", ["scalar_rgb", "llvm_ad_rgb"])
def test_lambert_inside_blendbsdf(variant):
    """The blend is the weighted sum of its parts, ctx.component selects one, and a sample's
    weight is eval / pdf; lambert blends as diffuse does."""
    mi.set_variant(variant)
    weight = 0.3
    si, ctx = _si([0, 0, 1]), mi.BSDFContext()
    results = {}
    for plugin in ("lambert", "diffuse"):
        white = mi.load_dict({"type": plugin, "reflectance": {"type": "rgb", "value": 1.0}})
        metal = mi.load_dict({"type": "roughconductor", "alpha": 0.3})
        blend = mi.load_dict({"type": "blendbsdf", "a": metal, "b": white, "weight": weight})
        assert blend.component_count() == 2
        wo = [0.3, 0.1, 0.9486833]
        expected = (1 - weight) * metal.eval(ctx, si, wo) + weight * white.eval(ctx, si, wo)
        assert dr.allclose(blend.eval(ctx, si, wo), expected)
        part = mi.BSDFContext()
        part.component = 1
        assert dr.allclose(blend.eval(part, si, wo), weight * white.eval(ctx, si, wo))
        samples = []
        for s1, s2 in ((0.1, [0.2, 0.9]), (0.6, [0.4, 0.6]), (0.9, (0.7, 0.2))):
            bs, w = blend.sample(ctx, si, s1, s2)
            value, pdf = blend.eval_pdf(ctx, si, wo=bs.wo)
            assert dr.allclose(w, value / pdf)
            samples.append(np.array(w, float).ravel())
        results[plugin] = np.array(samples)
    np.testing.assert_allclose(results["lambert"], results["diffuse"], rtol=1e-5)


@pytest.mark.parametrize("variant", ["scalar_rgb", "llvm_ad_rgb"])
def test_lambert_inside_normalmap(variant):
    """A flat normal map changes nothing; a normal that leaves wi below gives 0 unless
    flipped; without the shadowing function a tilted normal gives the full response."""
    mi.set_variant(variant)
    ctx = mi.BSDFContext()

    def mapped(normal, **options):
        return mi.load_dict({"type": "normalmap", "nested_bsdf": {"type": "lambert"},
                             "normalmap": {"type": "rgb", "value": [0.5 * c + 0.5 for c in normal]},
                             **options})

    plain, flat = mi.load_dict({"type": "lambert"}), mapped([0, 0, 1])
    si = _si([0.3, 0.2, 0.9327379])
    for s1, s2 in ((0.2, [0.1, 0.3]), (0.7, [0.8, 0.6])):
        (bs_a, w_a), (bs_b, w_b) = plain.sample(ctx, si, s1, s2), flat.sample(ctx, si, s1, s2)
        assert dr.allclose(w_a, w_b, atol=1e-5) and dr.allclose(bs_a.wo, bs_b.wo, atol=1e-5)

    n = [float(c) for c in np.array([1, 1, 1]) / np.sqrt(3)]
    si = _si([float(c) for c in np.array([-1, -1, 0.5]) / 1.5])
    assert dr.allclose(mapped(n, flip_invalid_normals=False).eval(ctx, si, [0, 0, 1]), 0)
    assert dr.all(mapped(n, flip_invalid_normals=True).eval(ctx, si, [0, 0, 1]) > 0)

    tilt = [float(c) for c in np.array([1, 0.01, 0.01]) / np.linalg.norm([1, 0.01, 0.01])]
    si = _si([0, 0, 1])
    full = mapped(tilt, use_shadowing_function=False)
    assert dr.allclose(full.eval(ctx, si, tilt), 0.5 * dr.inv_pi, atol=1e-2)
    assert dr.all(mapped(tilt, use_shadowing_function=True).eval(ctx, si, tilt) < 0.01)


@pytest.mark.parametrize("variant", VARIANTS + ["llvm_ad_mono", "scalar_spectral_polarized"])
def test_lambert_returns_what_diffuse_returns(variant):
    """Every entry point called with Python lists and floats, ``active`` left out, gives
    lambert's values of the types and shapes that diffuse gives: Mueller matrices in the
    polarized variants (the albedo times the identity, as diffuse's
    ``eval_diffuse_reflectance``), wide arrays when a JIT variant's si or wo is wide."""
    mi.set_variant(variant)
    ctx = mi.BSDFContext()
    mine, theirs = mi.load_dict({"type": "lambert"}), mi.load_dict({"type": "diffuse"})
    wi, wo = [0.3, 0.2, 0.9327379], [-0.5, 0.1, 0.8602325]
    calls = {
        "eval": lambda b: b.eval(ctx, _si(wi), wo=wo),
        "pdf": lambda b: b.pdf(ctx, _si(wi), wo),
        "eval_pdf": lambda b: b.eval_pdf(ctx, _si(wi), tuple(wo)),
        "sample": lambda b: b.sample(ctx, _si(wi), 0.5, [0.3, 0.6]),
        "eval_pdf_sample": lambda b: b.eval_pdf_sample(ctx, _si(wi), wo, 0.5, [0.3, 0.6]),
        "eval_diffuse_reflectance": lambda b: b.eval_diffuse_reflectance(_si(wi)),
        "below": lambda b: b.eval(ctx, _si([0.3, 0.2, -0.93]), wo),
    }
    if dr.is_jit_v(mi.Float):
        wide = mi.Vector3f([0.3, 0.1, 0.0], [0.2, 0.0, 0.0], [0.93, 0.99, -1.0])
        calls.update({
            "eval, wide si": lambda b: b.eval(ctx, _si(wide), wo),
            "eval, wide wo": lambda b: b.eval(ctx, _si(wi), wide),
            # (the weight: where wi is below, diffuse leaves the sample's pdf, we zero it)
            "sample, wide si": lambda b: b.sample(ctx, _si(wide), 0.5, [0.3, 0.6])[1],
            "sample, wide samples": lambda b: b.sample(ctx, _si(wi), mi.Float([0.1, 0.5]),
                                                       mi.Point2f([0.1, 0.9], [0.2, 0.4])),
        })

    def parts(x):
        if isinstance(x, tuple):
            return [p for y in x for p in parts(y)]
        if isinstance(x, mi.BSDFSample3f):
            return parts((x.wo, x.pdf, x.eta))
        return [(type(x).__name__, np.array(x, dtype=float))]

    for name, call in calls.items():
        got, want = parts(call(mine)), parts(call(theirs))
        assert [t for t, _ in got] == [t for t, _ in want], (variant, name, got, want)
        for (_, a), (_, b) in zip(got, want):
            a, b = np.broadcast_arrays(a, b)
            np.testing.assert_allclose(a, b, rtol=1e-5, atol=1e-7, err_msg=f"{variant} {name}")
