"""Hard cases every plugin shares: nearly opposite grazing directions, parameters past their
range at load and through ``params.update()``, and the precision of terms that cancel.

The tests loop over ``mitsuba_brdfs.plugin_models()`` and take each model's settings from
its module (``FACTS``: ``edges``, ``float64``, ``colour``), so a new model is checked here
without being listed.
"""
import math
import re

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

import reference as R
from checks import (CORNERS, FACTS, check_declared, check_eval_pdf_finite, check_samples_finite,
                    corner_samples, hard_directions, hard_pairs, small_scene, unit)
from mitsuba_brdfs.validate.directions import nearly_opposite_grazing
from checks import floats, interaction, point2, to_np, vec
from mitsuba_brdfs import ParameterError, plugin_models
from mitsuba_brdfs.bsdf_xml import dict_to_xml
from mitsuba_brdfs.core.numerics import one_minus_pow5

PLUGINS = sorted(plugin_models())


def settings():
    """Every model at its defaults and at the edges of its ranges (its ``FACTS.edges``)."""
    return [(name, kw) for name in PLUGINS for kw in [{}] + list(FACTS[name].edges)]


@pytest.mark.parametrize("name", PLUGINS)
def test_every_model_declares_edges_references_and_a_colour(name):
    """The per-model settings of this file come from the models' own declarations: a new
    model is not silently left out of them."""
    check_declared(name, "edges", "float64", "colour")


def _ids(case):
    name, kw = case
    return name + "".join(f"-{k}={v}" for k, v in kw.items())


# -- 1. nearly opposite grazing directions -----------------------------------------------------

@pytest.mark.parametrize("case", settings(), ids=_ids)
def test_opposite_grazing_pairs_are_finite_and_non_negative(case):
    """eval, pdf and eval_pdf on the whole family (and the shared grid of hard directions) are
    finite and >= 0, in both roles of wi and wo."""
    name, kw = case
    b = mi.load_dict({"type": name, **kw})
    wi, wo = nearly_opposite_grazing(4000, seed=1)
    d = hard_directions()
    hi, ho = hard_pairs(d)
    for a, c in ((wi, wo), (wo, wi), (hi, ho)):
        check_eval_pdf_finite(b, mi.BSDFContext(), a, c, tag=(name, kw))
        for f in (b.eval(mi.BSDFContext(), interaction(a), vec(c)),
                  b.pdf(mi.BSDFContext(), interaction(a), vec(c))):  # alone, as eval_pdf
            assert np.isfinite(to_np(f)).all() and (to_np(f) >= 0).all(), (name, kw)


@pytest.mark.parametrize("case", settings(), ids=_ids)
def test_samples_at_grazing_incidence_are_finite(case):
    """Sampling with wi 1e-8 .. 1e-2 rad above the horizon (corner and random samples): weights
    and pdfs finite and >= 0, directions unit vectors."""
    name, kw = case
    b = mi.load_dict({"type": name, **kw})
    wi, _ = nearly_opposite_grazing(12, seed=2)
    check_samples_finite(b, mi.BSDFContext(), corner_samples(wi, CORNERS, CORNERS), tag=(name, kw))
    rng = np.random.default_rng(3)
    n = 20000
    si = interaction(np.repeat(wi, n // len(wi), axis=0))
    m = dr.width(si.wi)
    bs, w = b.sample(mi.BSDFContext(), si, floats(rng.random(m)),
                     point2(*rng.random((2, m))))
    w, pdf = to_np(w), to_np(bs.pdf)
    assert np.isfinite(w).all() and (w >= 0).all(), (name, kw)
    assert np.isfinite(pdf).all() and (pdf >= 0).all(), (name, kw)


#: (plugin, parameters, relative tolerance) against reference.f (float64, without the cosine):
#: every model's ``FACTS.float64``
REFERENCES = [(name, kw, rtol) for name in PLUGINS for kw, rtol in FACTS[name].float64]


@pytest.mark.parametrize("name,kw,rtol", REFERENCES, ids=[_ids((r[0], r[1])) for r in REFERENCES])
def test_opposite_grazing_pairs_match_float64(name, kw, rtol):
    """Where the float32 directions fix the half vector (|wi + wo| >= 1e-3: their rounding
    moves it by at most ~1e-4 rad), eval agrees with the float64 formula, values up to 1e5
    at 0.1 degree above the horizon included. Below that, the direction the float32 numbers
    stand for is itself uncertain to more than the value's precision."""
    b = mi.load_dict({"type": name, **kw})
    wi, wo = nearly_opposite_grazing(20000)
    ui, uo = unit(wi), unit(wo)
    with np.errstate(all="ignore"):
        want = R.f(name, ui, uo, **kw)[:, 0] * uo[:, 2]
    got = to_np(b.eval(mi.BSDFContext(), interaction(wi), vec(wo)))[:, 0]
    ok = (np.linalg.norm(ui + uo, axis=1) >= 1e-3) & (want > 1e-30)
    assert ok.sum() > 10000
    np.testing.assert_allclose(got[ok], want[ok], rtol=rtol, err_msg=name)


@pytest.mark.parametrize("variant", ["llvm_ad_rgb", "scalar_rgb"])
def test_ashikhmin_shirley_opposite_grazing_pair(variant):
    """The pair that gave eval = pdf = -115.5 (float64: +702.8) before the half vector's cosine
    was taken from |wi + wo|."""
    mi.set_variant(variant)
    b = mi.load_dict({"type": "ashikhmin_shirley", "nu": 0.01, "nv": 0.01})
    wi = np.array([-0.16400671, -0.98645920, 1.8063385e-08], np.float32)
    wo = np.array([0.16389868, 0.98647720, 2.6500562e-05], np.float32)
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(*map(float, wi))
    f, pdf = b.eval_pdf(mi.BSDFContext(), si, mi.Vector3f(*map(float, wo)))
    ui, uo = unit(wi[None].astype(float)), unit(wo[None].astype(float))
    want = sum(R.ashikhmin_shirley(ui, uo, 0.05, 0.5, 0.01, 0.01))[0, 0] * uo[0, 2]
    assert abs(want - 702.8) < 0.1
    np.testing.assert_allclose(np.array(f).ravel()[0], want, rtol=1e-4)
    assert np.array(pdf).ravel()[0] > 0


# -- 2 and 3. ranges, at load and through params.update() ----------------------------------------

def bounded_parameters():
    """(plugin, parameter, range) for every parameter with a checked range."""
    out = []
    for name in PLUGINS:
        for param, rng in mi.load_dict({"type": name})._ranges.items():
            out.append((name, param, rng))
    return out


def outside(rng):
    """Values just past each finite end of the range, far past it, and NaN."""
    vals = [math.nan]
    if math.isfinite(rng.lo):
        vals += [rng.lo - max(1e-3, abs(rng.lo) * 0.01), -1e20]
    if math.isfinite(rng.hi):
        vals += [rng.hi * 1.01 + 1e-3, 1e20]
    return vals


BOUNDED = bounded_parameters()


def test_every_model_has_checked_ranges():
    assert {b[0] for b in BOUNDED} == set(PLUGINS)
    # the exponents are bounded above (beyond 1e6 a lobe is narrower than float32 resolves)
    for name, param in [("phong", "exponent"), ("blinn_phong", "exponent"),
                        ("torrance_sparrow", "exponent"), ("ashikhmin_shirley", "nu"),
                        ("ashikhmin_shirley", "nv")]:
        assert dict(((b[0], b[1]), b[2]) for b in BOUNDED)[(name, param)].hi == 1e6


@pytest.mark.parametrize("name,param,rng", BOUNDED, ids=[f"{b[0]}-{b[1]}" for b in BOUNDED])
def test_out_of_range_refused_at_load_and_update(name, param, rng):
    """A value past the range is refused when loading and when set through mi.traverse, with
    one message naming plugin, parameter and range; the ends of the range are accepted."""
    scene = small_scene({"type": name})
    params = mi.traverse(scene)
    key = next(k for k in params.keys() if k.startswith(f"ball.bsdf.{param}."))
    old = params[key]
    for v in outside(rng):
        with pytest.raises(RuntimeError) as load_err:
            mi.load_dict({"type": name, param: v})
        params[key] = type(old)(v)
        with pytest.raises(ParameterError) as update_err:
            params.update()
        msg = str(update_err.value)
        assert msg.startswith(f"{name}: parameter '{param}' must be {rng.expected}"), msg
        assert msg in str(load_err.value)  # the same message, the refused value included
        # the refused value is taken back: the plugin keeps the last accepted one
        np.testing.assert_array_equal(np.array(params[key]), np.array(old))
    for v in (rng.lo, rng.hi):
        if math.isfinite(v):
            mi.load_dict({"type": name, param: float(v)})
            params[key] = type(old)(v)
            params.update()


@pytest.mark.parametrize("name,param,rng", BOUNDED, ids=[f"{b[0]}-{b[1]}" for b in BOUNDED])
def test_out_of_range_bitmaps_refused_at_load(name, param, rng, tmp_path):
    """A bitmap (a file, as users give them) of a value past the range is refused, with the
    same message as the number (its channels: one for a float parameter, three for a
    colour)."""
    bad = next(v for v in outside(rng) if math.isfinite(v))
    path = str(tmp_path / "bad.exr")
    mi.Bitmap(np.full((2, 2, 1 if rng.scalar else 3), bad, np.float32)).write(path)
    with pytest.raises(RuntimeError, match=rf"{name}: parameter '{param}' must be "
                                           rf"{re.escape(rng.expected)}"):
        mi.load_dict({"type": name, param: {"type": "bitmap", "filename": path, "raw": True}})


def _refused(name, props):
    """The one-line message of loading ``name`` with ``props``, from a dict and from XML
    (``bsdf_xml``): the same in both."""
    with pytest.raises(RuntimeError) as from_dict:
        mi.load_dict({"type": name, **props})
    with pytest.raises(RuntimeError) as from_xml:
        mi.load_string(dict_to_xml({"type": name, **props}, version=True))
    said = str(from_dict.value).strip().splitlines()[-1]
    said = said[said.index(f"{name}: parameter"):]
    assert said in str(from_xml.value), (said, str(from_xml.value)[-300:])
    return said


def wrong_kinds():
    """(plugin, parameter, value, what its message says) for values of the wrong kind:
    text for a number, infinity, a colour with one channel past the range, text or a number
    for a boolean, an unknown or non-text choice."""
    out = []
    for name, param, rng in BOUNDED:
        expected = f"must be {rng.expected}"
        out += [(name, param, "rough", expected), (name, param, math.inf, expected)]
        if not rng.scalar and math.isfinite(rng.hi):
            out.append((name, param, {"type": "rgb", "value": [0.2, rng.hi + 0.5, 0.3]},
                        expected))
    for name in PLUGINS:
        for option, values in mi.load_dict({"type": name}).OPTIONS.items():
            if isinstance(values[0], bool):
                out += [(name, option, "yes", "must be a boolean"),
                        (name, option, 1, "must be a boolean")]
            else:
                out += [(name, option, "__bogus__", "must be one of"),
                        (name, option, 3.0, "must be one of")]
    return out


@pytest.mark.parametrize("name,param,value,says", wrong_kinds(),
                         ids=[f"{w[0]}-{w[1]}-{w[2]!r}" for w in wrong_kinds()])
def test_wrong_kinds_refused_in_dicts_and_xml(name, param, value, says):
    """One line naming the plugin, the parameter and what it takes, the same from a dict
    and from a scene file."""
    assert _refused(name, {param: value}).startswith(f"{name}: parameter '{param}' {says}")


def _valid(name, param):
    """A value ``param`` of ``name`` accepts (its documented default, or inside its range)."""
    from mitsuba_brdfs.docstrings import parameters
    p = next(q for q in parameters(name) if q.name == param)
    text = p.default.strip("`")
    if p.type == "string":
        return text
    try:
        return float(text)
    except ValueError:  # (no default value: inside the range, or a grey for a texture)
        return (p.bounds()[0] + p.bounds()[1]) / 2 if p.bounds() else 0.5


def broken_relations():
    """(plugin, properties, the parameter refused) breaking each relation its model
    declares (``RELATIONS``, ``core.relations``)."""
    from mitsuba_brdfs.core import relations as R_
    from mitsuba_brdfs.core.registry import models
    out = []
    for name in PLUGINS:
        options = models()[name].OPTIONS
        for rel in models()[name].RELATIONS:
            if isinstance(rel, R_.Together):
                out.append((name, {rel.names[0]: _valid(name, rel.names[0])}, rel.names[1]))
            elif isinstance(rel, R_.Excludes):
                given = rel.second if rel.every else rel.second[:1]
                props = {n: _valid(name, n) for n in (rel.first[0],) + given}
                out.append((name, props, rel.first[0]))
            elif isinstance(rel, R_.Only):
                other = next(v for v in options[rel.option] if v != rel.value)
                out.append((name, {rel.option: other, rel.names[0]: _valid(name, rel.names[0])},
                            rel.names[0]))
            elif isinstance(rel, R_.Absent):
                out.append((name, {rel.names[0]: 0.1}, rel.names[0]))
    return out


@pytest.mark.parametrize("name,props,refused", broken_relations(),
                         ids=[f"{b[0]}-{'-'.join(b[1])}" for b in broken_relations()])
def test_broken_relations_refused_in_dicts_and_xml(name, props, refused):
    """Each relation between parameters a model declares is refused when broken, naming
    the parameter, from a dict and from a scene file."""
    assert _refused(name, props).startswith(f"{name}: parameter '{refused}' must be")


@pytest.mark.parametrize("name", PLUGINS)
def test_update_with_bad_bitmap_data_refused(name):
    """A texture whose data is changed through traverse is checked as at load (a reflectance
    bitmap set to 1.5, then to -1, then NaN)."""
    colour = FACTS[name].colour
    arr = np.full((2, 2, 3), 0.5, np.float32)
    tex = {"type": "bitmap", "data": mi.TensorXf(arr), "raw": True}
    scene = small_scene({"type": name, colour: tex})
    params = mi.traverse(scene)
    key = f"ball.bsdf.{colour}.data"
    for bad in (1.5, -1.0, math.nan):
        params[key] = mi.TensorXf(np.full((2, 2, 3), bad, np.float32))
        with pytest.raises(ParameterError, match=f"{name}: parameter '{colour}' must be a reflectance"):
            params.update()
    params[key] = mi.TensorXf(np.full((2, 2, 3), 0.25, np.float32))
    params.update()


def test_refused_update_renders_the_last_accepted_values():
    """A caught refusal (an optimisation loop may catch it) leaves the BSDF as it was: the
    render equals the one before the bad value was set."""
    scene = small_scene({"type": "ward", "alpha_u": 0.2}, res=8)
    before = np.array(mi.render(scene, spp=4, seed=1))
    params = mi.traverse(scene)
    for key, bad in (("ball.bsdf.alpha_u.value", -1.0),
                     ("ball.bsdf.diffuse_reflectance.value", 1.2)):
        params[key] = bad
        with pytest.raises(ParameterError):
            params.update()
        # the same values, though not always the same kernel (an update may make a value
        # opaque that the first render baked in): equal to float32 rounding
        np.testing.assert_allclose(np.array(mi.render(scene, spp=4, seed=1)), before,
                                   rtol=1e-5, atol=1e-6)


def test_phong_p_1e20_refused_and_1e6_keeps_its_lobe():
    """p = 1e20 used to load and lose its lobe; 1e6 (the top of the range) reflects about
    ks N(p)... at 30 degrees: the specular albedo of the normalized form is ~ks cos."""
    with pytest.raises(RuntimeError, match=r"phong: parameter 'exponent' .*\[0, 1e6\] \(got 1e\+?20"):
        mi.load_dict({"type": "phong", "exponent": 1e20})
    b = mi.load_dict({"type": "phong", "exponent": 1e6, "diffuse_reflectance": 0.0,
                      "specular_reflectance": 1.0})
    si = interaction(np.repeat([[0.5, 0, math.sqrt(0.75)]], 100000, axis=0))
    rng = np.random.default_rng(0)
    _, w = b.sample(mi.BSDFContext(), si, floats(rng.random(100000)),
                    point2(*rng.random((2, 100000))))
    assert abs(to_np(w).mean() - math.sqrt(0.75)) < 0.01


def test_fit_keeps_parameters_in_range(tmp_path):
    """The inverse-rendering example clamps its parameters into range after each step (a
    learning rate that throws them far out must not stop it)."""
    from mitsuba_brdfs import image_fit as fit
    result = fit.fit(iterations=3, spp=1, res=8, lr=50.0, tile_res=8, target_spp=1,
                     out=str(tmp_path), progress=None)
    assert 0 <= result["final"]["rs"] <= 1
    assert 0 <= result["final"]["nu"] <= 1e6 and 0 <= result["final"]["nv"] <= 1e6


# -- 4. precision of terms that cancel ---------------------------------------------------------

def test_one_minus_pow5_is_exact_for_small_arguments():
    # down to 1e-30: float32 kernels flush denormals (results below 1.2e-38) to zero
    y = np.concatenate([10.0 ** -np.arange(1, 31, 0.5), np.linspace(0, 1, 101)]).astype(np.float32)
    got = np.array(one_minus_pow5(floats(y)))
    y64 = y.astype(float)
    with np.errstate(divide="ignore"):
        want = -np.expm1(5 * np.log1p(-y64))
    np.testing.assert_allclose(got, want, rtol=4e-7, atol=0)


def test_ashikhmin_shirley_diffuse_term_at_grazing():
    """Eq. 5's 1 - (1 - n.k/2)^5 keeps its precision at n.k = 7.7e-7 (it lost 7% there)."""
    b = mi.load_dict({"type": "ashikhmin_shirley", "specular_reflectance": 0.05,
                      "diffuse_reflectance": 0.5})
    ctx = mi.BSDFContext()
    ctx.component = 1
    c = np.array([7.7e-7, 3e-8, 1e-4, 1e-2], np.float32).astype(float)
    wi = np.stack([np.sqrt(1 - c * c), 0 * c, c], -1)
    wo = np.stack([0 * c, np.sqrt(1 - c[::-1] ** 2), c[::-1]], -1)
    got = to_np(b.eval(ctx, interaction(wi), vec(wo)))[:, 0]
    _, want = R.ashikhmin_shirley(unit(wi.astype(np.float32).astype(float)),
                                  unit(wo.astype(np.float32).astype(float)), 0.05, 0.5, 100, 100)
    want = want[:, 0] * unit(wo.astype(np.float32).astype(float))[:, 2]
    np.testing.assert_allclose(got, want, rtol=1e-5)
