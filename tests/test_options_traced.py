"""A family option chosen at load time traces only its own branch.

Each option (a Phong form, the Blinn-Phong normalisation, a Ward form, a microfacet
distribution or shadowing term, a Toon highlight or colour ramps, the Oren-Nayar table, form
and sampling, a roughness instead of exponents, cosine-only sampling) selects Python
functions in the plugin's constructor. Tracing ``eval``, ``pdf``, ``eval_pdf`` and ``sample`` runs exactly the Python
code that ends up in the kernel, so recording which functions run proves that the other
options' code is not traced (a ``dr.select`` over every option would run all of them).
"""

import pytest

from checks import codes, traced_code
from mitsuba_brdfs.core import microfacet as M
from mitsuba_brdfs.core import roughness as R
from mitsuba_brdfs.core.shading import band
from mitsuba_brdfs.models import _phong_family as PF
from mitsuba_brdfs.models import ashikhmin_shirley as AS
from mitsuba_brdfs.models import blinn_phong as BP
from mitsuba_brdfs.models import oren_nayar as ON
from mitsuba_brdfs.models import oren_nayar_eon as EON
from mitsuba_brdfs.models import toon as T
from mitsuba_brdfs.models import ward as W


def methods(cls):
    return {v.__code__ for v in vars(cls).values() if hasattr(v, "__code__")}


def check(d, own, others):
    seen = traced_code(d)
    assert own & seen, f"{d}: its own option's code did not run (the check would be void)"
    leaked = others & seen
    assert not leaked, f"{d}: traced code of other options: {sorted(c.co_name for c in leaked)}"


@pytest.mark.parametrize("plugin", ["phong", "blinn_phong"])
@pytest.mark.parametrize("form", PF.FORMS)
def test_phong_family_form(plugin, form):
    by_form = {f: codes(PF._FACTORS[f], PF._ALBEDOS[f]) for f in PF.FORMS}
    others = set().union(*(c for f, c in by_form.items() if f != form))
    check({"type": plugin, "form": form}, by_form[form], others)


@pytest.mark.parametrize("normalization", ["exact", "approximate"])
def test_blinn_phong_normalization(normalization):
    by_kind = {k: codes(f) for k, f in BP.NORMALIZATIONS.items()}
    others = set().union(*(c for k, c in by_kind.items() if k != normalization))
    check({"type": "blinn_phong", "normalization": normalization}, by_kind[normalization], others)


@pytest.mark.parametrize("form", W.FORMS)
def test_ward_form(form):
    by_form = {f: codes(W._SHAPES[f]) for f in W.FORMS}
    others = set().union(*(c for f, c in by_form.items() if f != form))
    check({"type": "ward", "form": form}, by_form[form], others)


@pytest.mark.parametrize("plugin,mapping", [("ashikhmin_shirley", R.half_vector_exponent),
                                            ("blinn_phong", R.half_vector_exponent),
                                            ("phong", R.mirror_lobe_exponent)])
@pytest.mark.parametrize("roughness", [False, True])
def test_roughness_instead_of_exponents(plugin, mapping, roughness):
    """alpha traces its exponent mapping (the model's own); exponents trace no mapping."""
    mappings = codes(R.half_vector_exponent, R.mirror_lobe_exponent)
    if roughness:
        check({"type": plugin, "alpha": 0.2}, codes(mapping), mappings - codes(mapping))
    else:
        seen = traced_code({"type": plugin})
        assert not mappings & seen


@pytest.mark.parametrize("distribution", ["beckmann", "blinn", "ggx"])
@pytest.mark.parametrize("geometry", ["cook_torrance", "ggx"])
def test_cook_torrance_distribution_and_geometry(distribution, geometry):
    dists = {"beckmann": methods(M.Beckmann), "blinn": methods(M.Blinn), "ggx": methods(M.GGX)}
    geoms = {"cook_torrance": codes(M.vgroove_g),
             "ggx": codes(M.smith_ggx_g, M.smith_ggx_g1, M.smith_ggx_g1_over_cos)}
    others = set().union(*(c for k, c in dists.items() if k != distribution),
                         *(c for k, c in geoms.items() if k != geometry))
    # GGX's visible-normal sampler uses its own Smith G1: only the shadowing term of
    # `geometry` is checked through the free functions
    if distribution == "ggx":
        others -= codes(M.smith_ggx_g1, M.smith_ggx_g1_over_cos)
    own = (dists[distribution] & {c for c in dists[distribution] if c.co_name == "eval"}) \
        | geoms[geometry]
    check({"type": "cook_torrance", "distribution": distribution, "geometry": geometry},
          own, others)


@pytest.mark.parametrize("visible", [False, True])
def test_cook_torrance_visible_normal_sampling(visible):
    sample_visible = {M.GGX.sample_visible.__code__, M.GGX.pdf_visible.__code__}
    plain = {M.GGX.sample.__code__, M.GGX.pdf.__code__}
    own, others = (sample_visible, plain) if visible else (plain, sample_visible)
    check({"type": "cook_torrance", "distribution": "ggx", "sample_visible": visible},
          own, others)


@pytest.mark.parametrize("model", ["phong", "blinn"])
def test_toon_specular_model(model):
    cos = {"phong": codes(T.phong_cosine), "blinn": codes(T.blinn_cosine)}
    check({"type": "toon", "specular_model": model}, cos[model],
          cos["blinn" if model == "phong" else "phong"])


@pytest.mark.parametrize("ramp", [False, True])
def test_toon_ramps(ramp):
    ramps, bands = codes(T.ramp_lookup), codes(band)
    d = {"type": "toon"}
    if ramp:
        grey = {"type": "rgb", "value": [0.5, 0.5, 0.5]}
        d.update(diffuse_ramp=grey, specular_ramp=grey)
    check(d, ramps if ramp else bands, bands if ramp else ramps)


@pytest.mark.parametrize("lut", [0, 16])
def test_oren_nayar_table(lut):
    analytic = codes(ON.OrenNayar._retro_analytic)
    table = codes(ON.OrenNayar._retro_lut)
    own, others = (table, analytic) if lut else (analytic, table)
    check({"type": "oren_nayar", "sigma": 0.5, "lut_resolution": lut}, own, others)


@pytest.mark.parametrize("form", ON.FORMS)
def test_oren_nayar_form(form):
    eon = codes(EON.eon_f, EON.fon_g)
    qualitative = codes(ON.OrenNayar._retro_analytic, ON.oren_nayar_ab)
    own, others = (eon, qualitative) if form == "energy_preserving" else (qualitative, eon)
    check({"type": "oren_nayar", "form": form}, own, others)


@pytest.mark.parametrize("sampling", ["cltc", "cosine"])
def test_oren_nayar_eon_sampling(sampling):
    cltc = codes(EON.eon_sample, EON.eon_pdf)
    if sampling == "cltc":
        check({"type": "oren_nayar", "form": "energy_preserving"}, cltc, set())
    else:
        check({"type": "oren_nayar", "form": "energy_preserving", "sampling": "cosine"},
              codes(EON.eon_f), cltc)


def test_ashikhmin_shirley_cosine_sampling_traces_no_half_vector_warp():
    half = codes(AS.AshikhminShirley._glossy_sample, AS.AshikhminShirley._glossy_pdf)
    check({"type": "ashikhmin_shirley", "sampling": "half_vector"}, half, set())
    diffuse = codes(AS.AshikhminShirley._diffuse_f)
    check({"type": "ashikhmin_shirley", "sampling": "cosine"}, diffuse, half)
