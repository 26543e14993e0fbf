"""The ``check`` command and the suite behind it: every model of the package passes it at
its documented defaults, a user's BSDF with a known flaw fails the check that measures that
flaw, Mitsuba's own BSDFs pass or fail with the property they lack, and the command line
keeps its promises (exit status, JSON, usage errors, the report)."""
import json
import os
import subprocess
import sys
import textwrap

import mitsuba as mi
import pytest

from mitsuba_brdfs import plugin_models
from mitsuba_brdfs.__main__ import main
from mitsuba_brdfs.check import load_bsdfs, parse_value, run_file
from mitsuba_brdfs.validate import suite

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
QUICK = suite.SETTINGS["quick"]

#: a user's Lambertian BSDF with one flaw, chosen by the string parameter ``flaw``: a pdf()
#: twice the density its sampler draws, a weight 1.3 x eval / pdf, NaN where wi grazes the
#: surface, negative values where wo grazes it, light below the horizon; "none" is sound
USER_BSDF = textwrap.dedent('''
    import drjit as dr
    import mitsuba as mi


    class Mine(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.flaw = props.get("flaw", "none")
            self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide]
            self.m_flags = self.m_components[0]

        def eval(self, ctx, si, wo, active=True):
            cos_o = dr.abs(wo.z) if self.flaw == "below" else dr.maximum(wo.z, 0)
            f = 0.8 * cos_o / dr.pi * (si.wi.z > 0)
            if self.flaw == "nan":
                f *= dr.sqrt(si.wi.z - 1e-6) / dr.sqrt(si.wi.z)
            if self.flaw == "negative":
                f *= 1.25 * wo.z - 0.25 * (wo.z > 0)
            return mi.Color3f(f)

        def pdf(self, ctx, si, wo, active=True):
            pdf = mi.warp.square_to_cosine_hemisphere_pdf(wo) * ((si.wi.z > 0) & (wo.z > 0))
            return 2 * pdf if self.flaw == "pdf" else pdf

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def sample(self, ctx, si, sample1, sample2, active=True):
            bs = dr.zeros(mi.BSDFSample3f, dr.width(sample2))
            bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
            bs.pdf = self.pdf(ctx, si, bs.wo)
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.DiffuseReflection)
            weight = self.eval(ctx, si, bs.wo) / bs.pdf
            if self.flaw == "weight":
                weight *= 1.3
            return bs, dr.select(bs.pdf > 0, weight, 0)

        def traverse(self, callback):
            pass

        def to_string(self):
            return f"Mine[flaw={self.flaw}]"


    mi.register_bsdf("mine", lambda props: Mine(props))
''')


@pytest.fixture(scope="module")
def user_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("user") / "mine.py"
    path.write_text(USER_BSDF)
    return str(path)


def run_cli(*args, cwd=ROOT):
    """The command in a fresh process; this checkout's package, whatever the directory."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [ROOT] + ([os.environ["PYTHONPATH"]] if os.environ.get("PYTHONPATH") else []))}
    return subprocess.run([sys.executable, "-m", "mitsuba_brdfs", "check", *args], cwd=cwd,
                          env=env, capture_output=True, text=True, timeout=300)


def statuses(results):
    return {r.name: r.status for r in results}


def failed(results):
    return {r.name for r in results if r.status == "FAIL"}


# -- the package's own models ------------------------------------------------------------------

#: what the defaults of a model lack, as its docstring says (reported, not failed)
NOTES = {"toon": {"reciprocity"}}


@pytest.mark.parametrize("plugin", sorted(plugin_models()))
def test_every_model_passes_at_its_defaults(plugin):
    results = suite.run(mi.load_dict({"type": plugin}), QUICK, plugin)
    assert not failed(results), [r.message for r in results if r.status == "FAIL"]
    assert {r.name for r in results if r.status == "NOTE"} == NOTES.get(plugin, set())
    assert [r.name for r in results] == [name for name, _ in suite.CHECKS]


@pytest.mark.slow
def test_the_lead_model_passes_the_thorough_suite():
    results = suite.run(mi.load_dict({"type": "ashikhmin_shirley"}), suite.SETTINGS["thorough"])
    assert not failed(results), [r.message for r in results if r.status == "FAIL"]


def test_an_energy_gain_fails_unless_allowed():
    """The original Blinn-Phong lobe at p = 1 reflects up to 5 times what it receives."""
    gain = mi.load_dict({"type": "blinn_phong", "form": "original", "exponent": 1.0,
                         "diffuse_reflectance": 0.0, "specular_reflectance": 1.0})
    r = suite.run(gain, QUICK, only=["energy"])[0]
    assert r.status == "FAIL" and r.numbers["largest"] > 2
    allowed = suite.run(gain, suite.Settings(**{**QUICK.__dict__, "allow_gain": True}),
                        only=["energy"])[0]
    assert allowed.status == "NOTE" and allowed.numbers["largest"] == r.numbers["largest"]


def test_a_lobe_too_sharp_for_the_histogram_is_not_a_failure():
    """At 85 degrees a GGX lobe of roughness 0.05 is thinner than the quick test's cells: the
    expected counts are off whatever the BSDF does (the cells integrate the pdf to another
    total than a finer quadrature), so the incidence is reported as inconclusive."""
    sharp = mi.load_dict({"type": "cook_torrance", "distribution": "ggx", "roughness": 0.05})
    r = suite.run(sharp, QUICK, only=["chi2"])[0]
    assert r.status == "PASS" and r.numbers["inconclusive"] == [85.0], r.message
    assert "inconclusive at 85 deg" in r.message and "too sharp" in r.message


# -- a user's BSDF with a known flaw -----------------------------------------------------------

#: flaw -> the checks that must fail, and checks that must not (each check measures its own)
FLAWS = {
    "none": (set(), {"chi2", "weight", "furnace", "hard_cases", "flags"}),
    "pdf": ({"chi2", "pdf", "furnace"}, {"weight", "eval_pdf", "hard_cases"}),
    "weight": ({"weight", "furnace", "energy"}, {"chi2", "pdf", "hard_cases"}),
    "nan": ({"hard_cases"}, {"chi2", "weight", "furnace"}),
    "negative": ({"hard_cases"}, {"chi2", "pdf"}),
    "below": ({"flags"}, {"chi2", "weight", "hard_cases"}),
}


@pytest.mark.parametrize("flaw", FLAWS)
def test_a_flawed_user_bsdf_fails_the_check_that_measures_its_flaw(user_file, flaw):
    run_file(user_file)  # as --load does it, once the variant is set
    (name, bsdf), = load_bsdfs("mine", {"flaw": flaw})
    results = suite.run(bsdf, QUICK, name)
    must_fail, must_pass = FLAWS[flaw]
    assert must_fail <= failed(results), statuses(results)
    assert not must_pass & failed(results), statuses(results)
    if flaw == "none":
        assert not failed(results)
    if flaw == "weight":
        r = next(r for r in results if r.name == "weight")
        assert r.numbers["weight_max_rel"] == pytest.approx(0.3, rel=1e-3)


# -- Mitsuba's own BSDFs -----------------------------------------------------------------------

#: plugin -> {check that fails: words its message must hold}: the properties they lack
MITSUBA = {
    "diffuse": {},
    # pdf() is not masked: NaN with wi on the horizon, non-zero for wo below it
    "roughplastic": {"hard_cases": ["non-finite pdf", "wi = (1.0, 0.0, 0.0)"],
                     "flags": ["pdf is not 0"]},
    # sampled from wi on or below the horizon: NaN directions and pdfs (weight 0)
    "roughconductor": {"hard_cases": ["non-finite sample_pdf", "non-finite wo"]},
    # declares a back side where it samples nothing but pdf() is not 0; numbers its sampled
    # lobes 0..3 whatever its components; ignores ctx.component; NaN directions at sample 0
    "principled": {"chi2": ["sample() draws nothing", "pdf() integrates to"],
                   "flags": ["component outside 0..1"],
                   "components": ["ctx.component is ignored"],
                   "hard_cases": ["non-finite wo"]},
}


def test_principled_gains_energy_once_white():
    """Mitsuba's principled (Disney) BSDF is not energy conserving: white, it reflects up to
    1.2 times what it receives at its default roughness."""
    white = mi.load_dict({"type": "principled", "base_color": {"type": "rgb", "value": [1, 1, 1]}})
    results = suite.run(white, QUICK, only=["energy", "furnace"])
    assert statuses(results) == {"energy": "FAIL", "furnace": "PASS"}
    energy = next(r for r in results if r.name == "energy")
    assert 1.1 < energy.numbers["largest"] < 1.3 and "above 1 at theta_i = 0" in energy.message


@pytest.mark.slow  # a study of Mitsuba's own plugins, not of ours
@pytest.mark.parametrize("plugin", MITSUBA)
def test_mitsubas_bsdfs_pass_or_report_what_they_lack(plugin):
    results = suite.run(mi.load_dict({"type": plugin}), QUICK, plugin)
    assert failed(results) == set(MITSUBA[plugin]), statuses(results)
    for r in results:
        for words in MITSUBA[plugin].get(r.name, []):
            assert words in r.message, (r.name, r.message)
    passed = {r.name for r in results if r.status == "PASS"}
    assert {"weight", "furnace", "energy", "reciprocity"} <= passed


# -- the command line --------------------------------------------------------------------------

def test_parse_value():
    assert parse_value("0.25") == 0.25 and parse_value("2") == 2.0
    assert parse_value("0.9,0.5,0.1") == {"type": "rgb", "value": [0.9, 0.5, 0.1]}
    assert parse_value("true") is True and parse_value("False") is False
    assert parse_value("ggx") == "ggx" and parse_value("nan") == "nan"
    assert parse_value("1,2") == "1,2"


def test_xml_defaults_are_set_with_p(tmp_path):
    path = tmp_path / "plastic.xml"
    path.write_text('<bsdf version="3.0.0" type="roughplastic" id="coat">'
                    '<default name="alpha" value="0.1"/><float name="alpha" value="$alpha"/>'
                    '</bsdf>')
    (name, bsdf), = load_bsdfs(str(path), {"alpha": "0.35"})
    assert name == "coat" and "alpha = [0.35]" in str(bsdf)
    with pytest.raises(ValueError, match="is a Shape plugin, not a BSDF"):
        load_bsdfs("sphere", {})


def test_a_bsdf_that_raises_fails_the_check_without_stopping_the_others(user_file):
    run_file(user_file)
    (_, bsdf), = load_bsdfs("mine", {})
    bsdf.eval = None  # eval() now raises in every check that calls it
    results = suite.run(bsdf, QUICK, only=["reciprocity", "hard_cases"])
    assert [r.status for r in results] == ["FAIL", "FAIL"]
    assert all(r.message.startswith("raised TypeError") for r in results)


def test_cli_flawed_plugin_exits_1_with_json(user_file):
    r = run_cli("mine", "--load", user_file, "-p", "flaw=weight", "--quick", "--json")
    assert r.returncode == 1, r.stderr
    doc = json.loads(r.stdout)
    assert doc["passed"] is False and doc["variant"] == "llvm_ad_rgb"
    (b,) = doc["bsdfs"]
    checks = {c["name"]: c for c in b["checks"]}
    assert checks["weight"]["status"] == "FAIL" and not checks["weight"]["passed"]
    assert checks["weight"]["numbers"]["weight_max_rel"] == pytest.approx(0.3, rel=1e-3)
    assert checks["chi2"]["status"] == "PASS"


def test_cli_checks_every_bsdf_of_a_scene_and_exits_0(user_file, tmp_path):
    scene = tmp_path / "scene.xml"
    scene.write_text('''<scene version="3.0.0">
        <shape type="sphere" id="a"><bsdf type="mine"/></shape>
        <shape type="sphere" id="b"><bsdf type="ashikhmin_shirley" id="metal">
            <float name="diffuse_reflectance" value="0"/></bsdf></shape>
    </scene>''')
    r = run_cli(str(scene), "--load", user_file, "--quick", cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "a: PASS" in r.stdout and "metal: PASS" in r.stdout and "FAIL" not in r.stdout
    assert os.listdir(tmp_path) == ["scene.xml"]  # writes nothing


@pytest.mark.parametrize("args, words", [
    (["nosuch"], "unknown plugin 'nosuch'"),
    (["roughplastic", "-p", "alpha"], "KEY=VALUE"),
    (["ward", "-p", "alpha_u=-1"], "alpha_u"),
    (["missing.xml"], "missing.xml"),
    (["diffuse", "--load", "broken.py"], "broken.py: SyntaxError"),
    (["diffuse", "--variant", "scalar_rgb"], "JIT variant"),
    (["diffuse", "--quick", "--thorough"], "not allowed with"),
])
def test_cli_usage_errors_exit_2_without_traceback(tmp_path, args, words):
    (tmp_path / "broken.py").write_text("def oops(:\n")
    r = run_cli(*args, cwd=tmp_path)
    assert r.returncode == 2 and words in r.stderr, r.stderr
    assert "Traceback" not in r.stderr + r.stdout


def test_report_writes_a_page_with_plots(tmp_path, capsys):
    out = tmp_path / "report"
    assert main(["check", "roughconductor", "--quick", "--report", str(out)]) == 1
    page = (out / "check.md").read_text()
    assert "## roughconductor: FAIL" in page and "| FAIL | hard_cases |" in page
    for png in ("roughconductor_chi2.png", "roughconductor_albedo.png"):
        assert (out / png).stat().st_size > 10_000 and f"]({png})" in page
    assert "roughconductor: FAIL" in capsys.readouterr().out
