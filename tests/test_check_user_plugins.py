"""``check`` on plugins written the ways Mitsuba's documentation and tutorials write them.

The suite calls a BSDF through Mitsuba's own entry points (``mi.BSDF.sample(bsdf, ...)``
with a full ``active`` mask, as an integrator does), so a Python plugin gets exactly the
arguments a render gives it and what it returns is converted as a render converts it. Each
plugin here is written in one of those styles, by this test:

- ``tinted``: the tutorial "Custom Python plugin" style: a tinted smooth dielectric (two
  delta lobes) whose methods take ``active`` without a default, whose ``eval`` and ``pdf``
  return the Python float 0.0 and ``eval_pdf`` the tuple (0.0, 0.0); it scales transmitted
  radiance by eta^2 whatever ``ctx.mode`` says, which gains energy in importance transport
  (``fixed=True``: only in radiance transport, as Mitsuba's ``dielectric`` does);
- ``docdiffuse``: the documentation's diffuse example style: ``active &= ...`` in place,
  ``mi.BSDFSample3f()`` filled with Python ints, a reflectance texture evaluated with
  ``active``, ``eval`` returning ``mi.Vector3f(0)`` for a disabled lobe.
"""
import textwrap

import mitsuba as mi
import pytest

from cmdline import run_many
from mitsuba_brdfs.spec import load_bsdfs
from mitsuba_brdfs.variant import run_file
from mitsuba_brdfs.validate import suite

QUICK = suite.SETTINGS["quick"]

TINTED = textwrap.dedent('''
    import drjit as dr
    import mitsuba as mi


    class Tinted(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.eta = props["eta"] if "eta" in props else 1.33
            self.tint = props["tint"] if "tint" in props else [0.3, 0.8, 0.3]
            self.fixed = props["fixed"] if "fixed" in props else False
            both = mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
            self.m_components = [mi.BSDFFlags.DeltaReflection | both,
                                 mi.BSDFFlags.DeltaTransmission | both]
            self.m_flags = self.m_components[0] | self.m_components[1]

        def sample(self, ctx, si, sample1, sample2, active):
            cos_i = mi.Frame3f.cos_theta(si.wi)
            r, cos_t, eta_it, eta_ti = mi.fresnel(cos_i, self.eta)
            mirror = (sample1 <= r) & active
            bs = mi.BSDFSample3f()
            bs.pdf = dr.select(mirror, r, 1.0 - r)
            bs.sampled_component = dr.select(mirror, mi.UInt32(0), mi.UInt32(1))
            bs.sampled_type = dr.select(mirror, mi.UInt32(+mi.BSDFFlags.DeltaReflection),
                                        mi.UInt32(+mi.BSDFFlags.DeltaTransmission))
            bs.wo = dr.select(mirror, mi.reflect(si.wi), mi.refract(si.wi, cos_t, eta_ti))
            bs.eta = dr.select(mirror, 1.0, eta_it)
            tinted = dr.lerp(mi.Color3f(self.tint), mi.Color3f(1.0), dr.clip(cos_i, 0.0, 1.0))
            scale = dr.square(eta_ti)
            if self.fixed and ctx.mode != mi.TransportMode.Radiance:
                scale = 1.0
            return bs, dr.select(mirror, tinted, mi.Color3f(scale))

        def eval(self, ctx, si, wo, active):
            return 0.0

        def pdf(self, ctx, si, wo, active):
            return 0.0

        def eval_pdf(self, ctx, si, wo, active):
            return 0.0, 0.0

        def traverse(self, callback):
            callback.put("tint", self.tint, mi.ParamFlags.Differentiable)

        def parameters_changed(self, keys):
            pass

        def to_string(self):
            return f"Tinted[eta={self.eta}, tint={self.tint}]"


    mi.register_bsdf("tinted", lambda props: Tinted(props))
''')

DOCDIFFUSE = textwrap.dedent('''
    import drjit as dr
    import mitsuba as mi


    class DocDiffuse(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.m_reflectance = mi.load_dict({"type": "rgb", "value": [0.45, 0.9, 0.9]})
            self.m_flags = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
            self.m_components = [self.m_flags]

        def sample(self, ctx, si, sample1, sample2, active):
            cos_theta_i = mi.Frame3f.cos_theta(si.wi)
            active &= cos_theta_i > 0
            bs = mi.BSDFSample3f()
            bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
            bs.pdf = mi.warp.square_to_cosine_hemisphere_pdf(bs.wo)
            bs.eta = 1.0
            bs.sampled_type = +mi.BSDFFlags.DiffuseReflection
            bs.sampled_component = 0
            value = self.m_reflectance.eval(si, active)
            return bs, dr.select(active & (bs.pdf > 0.0), value, mi.Vector3f(0))

        def eval(self, ctx, si, wo, active):
            if not ctx.is_enabled(mi.BSDFFlags.DiffuseReflection):
                return mi.Vector3f(0)
            cos_theta_i = mi.Frame3f.cos_theta(si.wi)
            cos_theta_o = mi.Frame3f.cos_theta(wo)
            value = self.m_reflectance.eval(si, active) * dr.inv_pi * cos_theta_o
            return dr.select((cos_theta_i > 0.0) & (cos_theta_o > 0.0), value, mi.Vector3f(0))

        def pdf(self, ctx, si, wo, active):
            if not ctx.is_enabled(mi.BSDFFlags.DiffuseReflection):
                return 0.0
            cos_theta_i = mi.Frame3f.cos_theta(si.wi)
            cos_theta_o = mi.Frame3f.cos_theta(wo)
            pdf = mi.warp.square_to_cosine_hemisphere_pdf(wo)
            return dr.select((cos_theta_i > 0.0) & (cos_theta_o > 0.0), pdf, 0.0)

        def to_string(self):
            return "DocDiffuse[]"


    mi.register_bsdf("docdiffuse", lambda props: DocDiffuse(props))
''')


@pytest.fixture(scope="module")
def plugin_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("plugins")
    (folder / "tinted.py").write_text(TINTED)
    (folder / "docdiffuse.py").write_text(DOCDIFFUSE)
    return folder


def _run(folder, name, params=None):
    run_file(str(folder / f"{name}.py"))  # as --load does it, once the variant is set
    (label, bsdf), = load_bsdfs(name, params or {})
    return {r.name: r for r in suite.run(bsdf, QUICK, label)}


def test_the_tutorial_plugin_gets_a_verdict_from_every_check(plugin_files):
    """Called without ``active``, 9 of its 10 checks would raise inside the suite; with it,
    and with its 0.0 converted as a render converts it, every check judges the plugin: it
    gains energy in importance transport, and says so. Its lobes are delta lobes only, so
    the checks that compare weights with eval and pdf say they have nothing to compare
    (SKIP) rather than pass on "0 against 0"."""
    results = _run(plugin_files, "tinted")
    assert not [r.message for r in results.values() if r.message.startswith("raised")]
    status = {name: r.status for name, r in results.items()}
    assert status == {"chi2": "SKIP", "weight": "SKIP", "eval_pdf": "PASS", "pdf": "PASS",
                      "furnace": "SKIP", "energy": "FAIL", "reciprocity": "PASS",
                      "hard_cases": "PASS", "flags": "PASS", "components": "WARN"}, status
    energy = results["energy"]
    # from below (180 deg), in green: 1.33^2 T transmitted and 0.8 R reflected (the tint)
    r = (0.33 / 2.33) ** 2
    assert energy.numbers["largest"] == pytest.approx(1.33 ** 2 * (1 - r) + 0.8 * r, rel=2e-3)
    assert "it scales by eta^2 in importance transport too" in energy.message
    assert "ctx.component" in results["components"].message


def test_the_tutorial_plugin_fixed_passes(plugin_files):
    """Scaled by eta^2 in radiance transport only, the same plugin conserves energy."""
    results = _run(plugin_files, "tinted", {"fixed": "true"})
    assert results["energy"].status == "PASS", results["energy"].message
    assert results["energy"].numbers["largest"] <= 1.001
    assert "FAIL" not in {r.status for r in results.values()}


def test_the_documentation_diffuse_passes(plugin_files):
    results = _run(plugin_files, "docdiffuse")
    assert not [r.message for r in results.values() if r.status == "FAIL"]
    assert results["furnace"].numbers["quadrature"][0] == pytest.approx([0.45, 0.9, 0.9],
                                                                        rel=2e-3)


def test_the_command_line_checks_them_in_jit_and_scalar_variants(plugin_files):
    """As a user runs it: ``--load`` the tutorial's file, in llvm_ad_rgb and in scalar_rgb
    (where each call is a scalar one, and ``active`` a Python bool)."""
    tinted, scalar, diffuse = run_many([
        ["check", "tinted", "--load", plugin_files / "tinted.py", "--quick"],
        ["check", "tinted", "--load", plugin_files / "tinted.py", "--quick", "-p",
         "fixed=true", "--variant", "scalar_rgb", "--only", "weight", "--only", "energy"],
        ["check", "docdiffuse", "--load", plugin_files / "docdiffuse.py", "--quick",
         "--variant", "scalar_rgb", "--only", "furnace"],
    ], cwd=plugin_files)
    assert tinted[0] == 1 and "raised" not in tinted[1], tinted
    assert "tinted: FAIL (1 of 7 checks failed: energy; 1 warned: components; 3 skipped)" in tinted[1]
    assert scalar[0] == 0, scalar
    assert "PASS  scalar" in scalar[1] and "tinted: PASS (2 checks; 1 skipped)" in scalar[1]
    assert diffuse[0] == 0 and "docdiffuse: PASS (2 checks)" in diffuse[1], diffuse


def test_mitsubas_dielectric_is_not_told_it_ignores_the_mode():
    """Mitsuba's own smooth dielectric conserves energy in importance transport."""
    r = suite.run(mi.load_dict({"type": "dielectric"}), QUICK, only=["energy"])[0]
    assert r.status == "PASS" and "eta^2 in importance transport too" not in r.message


#: a delta mirror written with a flaw users make: eval returns the mirror's colour everywhere
#: (a smooth lobe that sample() never draws); pdf() is 0 as for a delta lobe
LEAKY = textwrap.dedent('''
    import drjit as dr
    import mitsuba as mi


    class Leaky(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.m_components = [mi.BSDFFlags.DeltaReflection | mi.BSDFFlags.FrontSide]
            self.m_flags = self.m_components[0]

        def sample(self, ctx, si, sample1, sample2, active=True):
            bs = mi.BSDFSample3f()
            bs.wo = mi.reflect(si.wi)
            bs.pdf = 1.0
            bs.eta = 1.0
            bs.sampled_type = +mi.BSDFFlags.DeltaReflection
            bs.sampled_component = 0
            return bs, mi.Color3f(0.9) & (mi.Frame3f.cos_theta(si.wi) > 0)

        def eval(self, ctx, si, wo, active=True):
            up = (mi.Frame3f.cos_theta(si.wi) > 0) & (mi.Frame3f.cos_theta(wo) > 0)
            return mi.Color3f(0.9 * dr.inv_pi * mi.Frame3f.cos_theta(wo)) & up

        def pdf(self, ctx, si, wo, active=True):
            return 0.0

        def to_string(self):
            return "Leaky[]"


    mi.register_bsdf("leaky", lambda props: Leaky(props))
''')


@pytest.mark.parametrize("plugin", ["dielectric", "conductor"])
def test_delta_lobes_only_skip_what_has_nothing_to_compare(plugin):
    """Mitsuba's smooth dielectric and conductor: every sample is of a delta lobe, so
    'weight' and 'furnace' are skipped with the reason, 'pdf' says why its integral is 0,
    and the summary counts the checks that judged."""
    results = {r.name: r for r in suite.run(mi.load_dict({"type": plugin}), QUICK, plugin)}
    for name in ("chi2", "weight", "furnace"):
        assert results[name].status == "SKIP", (name, results[name].message)
    assert "delta lobe" in results["weight"].message
    assert "eval is 0 off the delta" in results["furnace"].message
    assert results["pdf"].status == "PASS" and "pdf() is 0 off the delta" in results["pdf"].message
    assert results["energy"].status == "PASS"
    assert "FAIL" not in {r.status for r in results.values()}


def test_a_delta_plugin_whose_eval_is_not_zero_fails_the_furnace(tmp_path):
    """Skipping needs eval to be 0 off the delta too: a delta mirror whose eval returns a
    diffuse lobe fails 'furnace' (the quadrature of eval is 0.9, the smooth weights 0)."""
    (tmp_path / "leaky.py").write_text(LEAKY)
    results = _run(tmp_path, "leaky")
    furnace = results["furnace"]
    assert furnace.status == "FAIL", furnace.message
    assert furnace.numbers["quadrature"][0] == pytest.approx([0.9] * 3, rel=1e-2)
    assert results["weight"].status == "SKIP"


def test_a_value_mitsuba_cannot_take_back_is_said_once_with_what_was_returned(plugin_files):
    """The tutorial's plugin builds its weights as ``mi.Color3f``: in a spectral variant
    Mitsuba cannot convert them to its Spectrum (its bare message: "std::bad_cast"). The
    first check that samples says what sample() returned and what the variant takes; the
    others, which raise the same, refer to it."""
    mi.set_variant("llvm_ad_spectral")
    try:
        results = _run(plugin_files, "tinted")
    finally:
        mi.set_variant("llvm_ad_rgb")
    weight = results["weight"]
    assert weight.status == "FAIL"
    assert weight.message.startswith(
        "raised TypeError: sample() returns (BSDFSample3f, Color3f) where llvm_ad_spectral "
        "takes (BSDFSample3f, Spectrum)"), weight.message
    assert "mi.Spectrum" in weight.message and "bad_cast" not in weight.message
    assert results["energy"].message == "raised the TypeError of 'weight' (above)"


#: a diffuse plugin written for scalar calls: a Python ``if`` on cos(theta_i)
SCALAR_ONLY = textwrap.dedent('''
    import drjit as dr
    import mitsuba as mi


    class ScalarOnly(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide]
            self.m_flags = self.m_components[0]

        def sample(self, ctx, si, sample1, sample2, active=True):
            bs = mi.BSDFSample3f()
            bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
            bs.pdf = mi.warp.square_to_cosine_hemisphere_pdf(bs.wo)
            bs.eta = 1.0
            bs.sampled_type = +mi.BSDFFlags.DiffuseReflection
            if mi.Frame3f.cos_theta(si.wi) <= 0:
                return bs, mi.Color3f(0)
            return bs, mi.Color3f(0.5)

        def eval(self, ctx, si, wo, active=True):
            return mi.Color3f(0.5 / dr.pi * dr.maximum(wo.z, 0))

        def pdf(self, ctx, si, wo, active=True):
            return mi.warp.square_to_cosine_hemisphere_pdf(wo)

        def to_string(self):
            return "ScalarOnly[]"


    mi.register_bsdf("scalaronly", lambda props: ScalarOnly(props))
''')


def test_a_plugin_written_for_scalar_calls_gets_verdicts_not_a_crash(tmp_path):
    """Checked in scalar_rgb, the suite runs in llvm_ad_rgb, where a Python ``if`` on an
    array raises: each check FAILs saying why (once), the scalar comparison is skipped
    with the reason, and the command ends with its summary and exit status 1 (it used to
    stop with an error, exit 2)."""
    (tmp_path / "scalaronly.py").write_text(SCALAR_ONLY)
    (code, out, err), = run_many([["check", "scalaronly", "--load", "scalaronly.py",
                                   "--quick", "--variant", "scalar_rgb"]], cwd=tmp_path)
    assert code == 1 and err == "", (code, err)
    out = " ".join(out.split())  # the lines as wrapped for the terminal, joined
    assert "use dr.select or masks" in out
    assert out.count("implicit conversion to 'bool'") == 2, out  # weight's, and scalar's
    assert "SKIP scalar nothing to compare the scalar values with" in out
    assert "scalaronly: FAIL (" in out
