"""The ``check`` command and the suite behind it: every model of the package passes it at
its documented defaults, a user's BSDF with a known flaw fails the check that measures that
flaw, Mitsuba's own BSDFs pass or fail with the property they lack, and the command line
keeps its promises (exit status, JSON, usage errors, the report)."""
import json
import os
import runpy
import subprocess
import sys

import mitsuba as mi
import numpy as np
import pytest

import user_bsdf
from checks import FACTS
from cmdline import run_many
from mitsuba_brdfs import plugin_models
from mitsuba_brdfs.__main__ import main
from mitsuba_brdfs.spec import load_bsdfs, parse_value
from mitsuba_brdfs.variant import run_file
from mitsuba_brdfs.validate import suite

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
QUICK = suite.SETTINGS["quick"]



@pytest.fixture(scope="module")
def user_file(tmp_path_factory):
    return user_bsdf.write(tmp_path_factory.mktemp("user") / "mine.py", "mine", reflectance=0.8)


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

@pytest.mark.parametrize("plugin", sorted(plugin_models()))
def test_every_model_passes_at_its_defaults(plugin):
    results = suite.run(mi.load_dict({"type": plugin}), QUICK, plugin)
    assert not failed(results), [r.message for r in results if r.status == "FAIL"]
    # what the defaults of a model lack, as its docstring says (reported, not failed)
    assert {r.name for r in results if r.status == "NOTE"} == set(FACTS[plugin].check_notes)
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

#: flaw -> the checks that must fail, checks that must not fail, and the checks that warn
#: (each check measures its own flaw)
FLAWS = {
    "none": (set(), {"chi2", "weight", "furnace", "hard_cases", "flags"}, set()),
    "pdf": ({"chi2", "pdf", "furnace"}, {"weight", "eval_pdf", "hard_cases"}, set()),
    "weight": ({"weight", "furnace", "energy"}, {"chi2", "pdf", "hard_cases"}, set()),
    # eval integrates to 1.6 where the weights say 0.8: energy fails by eval's quadrature
    "cosine": ({"weight", "furnace", "energy"}, {"chi2", "pdf", "hard_cases"}, set()),
    "nan": ({"hard_cases"}, {"chi2", "weight", "furnace"}, set()),
    "negative": ({"hard_cases"}, {"chi2", "pdf"}, set()),
    "below": ({"flags"}, {"chi2", "weight", "hard_cases"}, set()),
    "masked": (set(), {"chi2", "weight", "pdf", "furnace", "hard_cases", "flags"},
               {"hard_cases", "flags"}),
}


@pytest.mark.parametrize("flaw", FLAWS)
def test_a_flawed_user_bsdf_fails_the_check_that_measures_its_flaw(user_file, flaw):
    run_file(user_file)  # as --load does it, once the variant is set
    (name, bsdf), = load_bsdfs("mine", {"flaw": flaw})
    results = suite.run(bsdf, QUICK, name)
    must_fail, must_pass, warn = FLAWS[flaw]
    assert must_fail <= failed(results), statuses(results)
    assert not must_pass & failed(results), statuses(results)
    assert {r.name for r in results if r.status == "WARN"} == warn, statuses(results)
    if flaw in ("none", "masked"):
        assert not failed(results)
    if flaw == "weight":
        r = next(r for r in results if r.name == "weight")
        assert r.numbers["weight_max_rel"] == pytest.approx(0.3, rel=1e-3)
    if flaw == "cosine":
        r = next(r for r in results if r.name == "energy")
        assert r.numbers["largest"] == pytest.approx(0.8, abs=1e-3), r.message
        assert r.numbers["largest_quadrature"] == pytest.approx(1.6, rel=0.01), r.message
        assert "above 1 by the eval at theta_i = 0" in r.message
        assert "above 1 by the mean weight" not in r.message
    if flaw == "masked":  # each warning has its count and an example
        hard = next(r for r in results if r.name == "hard_cases")
        (w,) = hard.warnings
        assert w["what"] == "non-finite or negative pdf where eval is 0" and w["count"] > 10
        assert "pdf = nan" in w["example"] and "at wi = " in w["example"]
        assert suite.summary(results) == (True, "PASS (10 checks; 2 warned: hard_cases, flags; "
                                                 "1 skipped)")
        assert suite.summary(results, strict=True)[0] is False


def test_summary_lines():
    r = [suite.Result("a", "PASS"), suite.Result("b", "WARN", warnings=[{}]),
         suite.Result("c", "SKIP")]
    assert suite.summary(r) == (True, "PASS (2 checks; 1 warned: b; 1 skipped)")
    assert suite.summary(r, strict=True) == (False, "FAIL (1 of 2 checks failed: b (warning, "
                                                    "--strict); 1 skipped)")
    r.append(suite.Result("d", "FAIL"))
    assert suite.summary(r) == (False, "FAIL (1 of 3 checks failed: d; 1 warned: b; 1 skipped)")
    assert suite.summary(r[:1]) == (True, "PASS (1 check)")
    assert suite.summary(r[2:3]) == (True, "PASS (0 checks; 1 skipped)")
    # as many warned as WARN lines, whatever the warnings each holds
    two = [suite.Result("e", "WARN", warnings=[{}, {}]), suite.Result("f", "WARN", warnings=[{}])]
    assert suite.summary(two) == (True, "PASS (2 checks; 2 warned: e, f)")


def test_assert_valid_lists_every_failed_check(user_file):
    from mitsuba_brdfs.validate import assert_valid
    run_file(user_file)
    with pytest.raises(AssertionError) as e:
        assert_valid({"type": "mine", "flaw": "weight"})
    text = str(e.value)
    assert text.startswith("mine: FAIL (3 of 10 checks failed: weight, furnace, energy; "
                           "1 skipped)\n")
    assert "  FAIL weight: " in text and "  FAIL furnace: " in text and "  FAIL energy: " in text
    results = assert_valid({"type": "mine", "flaw": "masked"}, only=["hard_cases"])
    assert [r.status for r in results] == ["WARN"]
    with pytest.raises(AssertionError, match="WARN hard_cases: .*pdf where eval is 0"):
        assert_valid({"type": "mine", "flaw": "masked"}, strict=True, only=["hard_cases"])
    with pytest.raises(ValueError, match="settings 'fast'"):
        assert_valid("diffuse", settings="fast")


def test_the_readme_testing_example_passes(monkeypatch):
    """examples/mydiffuse: the plugin file and its pytest file that the README shows."""
    folder = os.path.join(ROOT, "examples", "mydiffuse")
    monkeypatch.syspath_prepend(folder)
    monkeypatch.delitem(sys.modules, "mydiffuse", raising=False)
    readme = open(os.path.join(ROOT, "README.md")).read()
    for name in ("mydiffuse.py", "test_mydiffuse.py"):  # shown as they are
        assert open(os.path.join(folder, name)).read().rstrip("\n") in readme, name
    tests = runpy.run_path(os.path.join(folder, "test_mydiffuse.py"))
    names = [k for k in tests if k.startswith("test_")]
    assert names == ["test_mydiffuse_passes_every_check"]
    for reflectance in (0.0, 0.5, 1.0):
        tests["test_mydiffuse_passes_every_check"](reflectance)


# -- Mitsuba's own BSDFs -----------------------------------------------------------------------

#: Mitsuba 3.9.1's BSDFs at their defaults, as the README's table gives them: the checks that
#: warn (none fails), with words their warnings must hold
MITSUBA = {
    "diffuse": {},
    # NaN sample pdfs and directions from wi on or below the horizon, with weight 0
    "roughconductor": {"hard_cases": ["pdf in a sample of weight 0",
                                      "non-finite sampled direction in a sample of weight 0"]},
    # pdf() NaN with wi on the horizon, not 0 across the surface, where eval is 0
    "roughplastic": {"hard_cases": ["pdf where eval is 0", "pdf in a sample of weight 0"],
                     "flags": ["pdf is not 0 with wo across the surface"]},
    "plastic": {},
    "conductor": {},
    "dielectric": {},
    "roughdielectric": {"hard_cases": ["pdf in a sample of weight 0"]},
    "thindielectric": {},
    # pdf() not 0 below, where it neither samples nor evaluates; sampled_component 0..3 of
    # 2 components; ctx.component ignored; NaN directions at the sample (0, 0), with weight 0
    "principled": {"chi2": ["sample() and eval() give nothing but pdf() is not 0"],
                   "flags": ["component outside 0..1"],
                   "components": ["ctx.component ignored"],
                   "hard_cases": ["non-finite sampled direction in a sample of weight 0"]},
    "twosided": {},
    # the nested BSDFs' sampled_component, not blendbsdf's
    "blendbsdf": {"components": ["samples of ctx.component = 1 from other components"]},
    # ctx.component = 0 selects the null lobe instead of the nested BSDF
    "mask": {"components": ["samples of ctx.component = 0 from other components",
                            "component 0's mean weight is not its quadrature"]},
}

_DIFFUSE = {"type": "diffuse"}
#: the wrappers around diffuse (the README's table)
WRAPPERS = {
    "twosided": {"type": "twosided", "bsdf": _DIFFUSE},
    "blendbsdf": {"type": "blendbsdf", "weight": 0.3, "bsdf_0": _DIFFUSE,
                  "bsdf_1": {"type": "diffuse", "reflectance": 0.2}},
    "mask": {"type": "mask", "opacity": 0.5, "bsdf": _DIFFUSE},
}


def check_mitsuba(plugin, settings):
    results = suite.run(mi.load_dict(WRAPPERS.get(plugin, {"type": plugin})), settings, plugin)
    assert not failed(results), [r.message for r in results if r.status == "FAIL"]
    warned = {r.name: r for r in results if r.status == "WARN"}
    assert set(warned) == set(MITSUBA[plugin]), statuses(results)
    for name, words in MITSUBA[plugin].items():
        for w in words:
            assert w in warned[name].message, (name, warned[name].message)
        assert all(x["count"] > 0 and x["example"] for x in warned[name].warnings)
    return results


#: the BSDFs whose checks the default settings exercise beyond the quick ones: glossy lobes
#: (more incidences and samples for the chi-square test and the furnace), transmission
#: (reciprocity with eta^2) and the principled model's lobes; the smooth, diffuse and
#: wrapped ones give the same verdicts at every setting (their quick run: below)
GLOSSY = ("roughconductor", "roughplastic", "roughdielectric", "principled")
#: the glossy ones also run quick where nothing else of the quick suite checks them: the
#: others are checked quick by tests of their own below (roughplastic's flags warning,
#: roughdielectric's reciprocity, principled's energy) and in full at the default settings
QUICK_TOO = ("roughconductor",)


@pytest.mark.parametrize("plugin", [p for p in MITSUBA if p not in GLOSSY or p in QUICK_TOO])
def test_mitsubas_bsdfs_pass_with_the_warnings_of_the_readme(plugin):
    check_mitsuba(plugin, QUICK)


@pytest.mark.slow
@pytest.mark.parametrize("plugin", GLOSSY)
def test_mitsubas_bsdfs_at_the_default_settings(plugin):
    """The README's table is measured at the default settings."""
    check_mitsuba(plugin, suite.SETTINGS["default"])


def test_transmission_is_reciprocal_with_the_eta2_factor():
    """Mitsuba's roughdielectric and dielectric satisfy f(a, b) / eta_a^2 = f(b, a) / eta_b^2
    with eta from their samples; without the factor (eta = 1) they would not."""
    from mitsuba_brdfs.validate.reciprocity import (delta_transmission_reciprocity,
                                                    interface_eta, transmission_reciprocity)
    from mitsuba_brdfs.validate.directions import random_pairs, sph
    rough, smooth = (mi.load_dict({"type": t}) for t in ("roughdielectric", "dielectric"))
    eta = interface_eta(rough)
    assert eta == pytest.approx(1.5046 / 1.000277, rel=1e-5) == interface_eta(smooth)
    a, b = random_pairs(2, 2000)
    b = b * [1, 1, -1]
    assert transmission_reciprocity(rough, a, b, eta)["max_rel"] < 1e-5
    assert not transmission_reciprocity(rough, a, b, 1.0)["ok"]
    wi = sph(np.radians([0, 40, 70]), 0.3)
    assert delta_transmission_reciprocity(smooth, wi, eta)["max_rel"] < 1e-5
    assert not delta_transmission_reciprocity(smooth, wi, 1.0)["ok"]
    r = suite.run(rough, QUICK, only=["reciprocity"])[0]
    assert r.status == "PASS" and r.numbers["eta"] == eta and "across the surface" in r.message


def test_principled_gains_energy_once_white():
    """Mitsuba's principled (Disney) BSDF is not energy conserving: white, it reflects up to
    1.2 times what it receives at its default roughness."""
    white = mi.load_dict({"type": "principled", "base_color": {"type": "rgb", "value": [1, 1, 1]}})
    results = suite.run(white, QUICK, only=["energy", "furnace"])
    assert statuses(results) == {"energy": "FAIL", "furnace": "PASS"}
    energy = next(r for r in results if r.name == "energy")
    assert 1.1 < energy.numbers["largest"] < 1.3, energy.message
    assert "above 1 by the mean weight at theta_i = 0" in energy.message
    assert "above 1 by the eval at theta_i = 0" in energy.message


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
    assert results[0].message.startswith("raised TypeError")
    # the same exception again: said once, the second check refers to the first
    assert results[1].message == "raised the TypeError of 'reciprocity' (above)"


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
    assert "mine (shape 'a'): PASS" in r.stdout and "metal: PASS" in r.stdout and "FAIL" not in r.stdout
    assert os.listdir(tmp_path) == ["scene.xml"]  # writes nothing


def test_the_bsdfs_of_a_scene_are_the_users_own(tmp_path):
    """A shape group's shapes are reached through its instances, whose own ``bsdf()`` is
    Mitsuba's grey default (not the user's); an area light's black default is left out."""
    scene = tmp_path / "scene.xml"
    scene.write_text('''<scene version="3.0.0">
        <shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1"/></emitter>
            <transform name="to_world"><translate z="3"/></transform></shape>
        <shape type="sphere" id="ball"><bsdf type="ward"/></shape>
        <shape type="shapegroup" id="g">
            <shape type="sphere"><bsdf type="lambert"/></shape>
            <shape type="disk"><bsdf type="roughplastic"/></shape>
        </shape>
        <shape type="instance"><ref id="g"/></shape>
        <shape type="instance"><ref id="g"/><transform name="to_world"><translate x="3"/>
            </transform></shape>
    </scene>''')
    mi.set_variant("llvm_ad_rgb")
    found = load_bsdfs(str(scene), {})
    assert [(name, b.class_name()) for name, b in found] == [
        ("ward (shape 'ball')", "Ward"), ("lambert (shape 0 of group 'g')", "Lambert"),
        ("roughplastic (shape 1 of group 'g')", "RoughPlastic")], found


#: bad invocations of ``check`` and words of their one-line message
USAGE_ERRORS = [
    (["nosuch"], "unknown plugin 'nosuch'"),
    (["roughplastic", "-p", "alpha"], "KEY=VALUE"),
    (["ward", "-p", "alpha_u=-1"], "alpha_u"),
    (["missing.xml"], "missing.xml"),
    (["diffuse", "--load", "broken.py"], "broken.py: SyntaxError"),
    (["diffuse", "--variant", "scalar_rgbx"], "unknown variant 'scalar_rgbx'"),
    (["diffuse", "--quick", "--thorough"], "not allowed with"),
]


@pytest.fixture(scope="module")
def usage_errors(tmp_path_factory):
    """Each bad invocation through ``main()``, all in one new process: [(status, out, err)].
    (``check`` in a process of its own: the tests below; a bad invocation's status as a
    process's exit status: tests/test_main.py.)"""
    folder = tmp_path_factory.mktemp("usage")
    (folder / "broken.py").write_text("def oops(:\n")
    return run_many([["check", *args] for args, _ in USAGE_ERRORS], cwd=folder)


@pytest.mark.parametrize("case", range(len(USAGE_ERRORS)),
                         ids=[" ".join(args) for args, _ in USAGE_ERRORS])
def test_cli_usage_errors_exit_2_without_traceback(usage_errors, case):
    words = USAGE_ERRORS[case][1]
    code, out, err = usage_errors[case]
    assert code == 2 and words in err, err
    assert "Traceback" not in err + out


def test_report_writes_a_page_with_plots(tmp_path, capsys):
    out = tmp_path / "report"
    assert main(["check", "roughconductor", "--quick", "--report", str(out)]) == 0
    page = (out / "check.md").read_text()
    assert "## roughconductor: PASS (10 checks; 1 warned: hard_cases; 1 skipped)" in page
    assert "| WARN | hard_cases |" in page
    for png in ("roughconductor_chi2.png", "roughconductor_albedo.png"):
        assert (out / png).stat().st_size > 10_000 and f"]({png})" in page
    assert "roughconductor: PASS (10 checks; 1 warned: hard_cases; 1 skipped)" in \
        capsys.readouterr().out


def test_cli_warnings_pass_unless_strict(capsys):
    args = ["check", "roughplastic", "--quick", "--only", "flags", "--json"]
    assert main(args) == 0
    (b,) = json.loads(capsys.readouterr().out)["bsdfs"]
    (flags,) = b["checks"]
    assert b["verdict"] == "PASS (1 check; 1 warned: flags)" and flags["status"] == "WARN"
    (w,) = flags["warnings"]
    assert w["count"] > 0 and w["what"].startswith("pdf is not 0 with wo across the surface")
    assert main(args + ["--strict"]) == 1
    doc = json.loads(capsys.readouterr().out)
    assert doc["strict"] is True and doc["bsdfs"][0]["verdict"] == \
        "FAIL (1 of 1 check failed: flags (warning, --strict))"


@pytest.mark.parametrize("flaw", ["none", "scalar", "divide"])
def test_cli_scalar_variant_is_compared_with_its_jit_twin(user_file, capsys, flaw):
    """In scalar_rgb the suite runs in llvm_ad_rgb, then the scalar plugin (the user's file
    run again in scalar_rgb) is compared with it: 1% more light in scalar fails, and so does
    a division by 0 that raises in scalar only."""
    code = main(["check", "mine", "--load", user_file, "-p", f"flaw={flaw}", "--variant",
                 "scalar_rgb", "--quick", "--only", "weight"])
    out = capsys.readouterr().out
    text = " ".join(out.split())  # messages are wrapped to the terminal's width
    assert "variant scalar_rgb (the suite in llvm_ad_rgb, then compared)" in text
    if flaw == "none":
        assert "scalar_rgb against llvm_ad_rgb on 382 direction pairs and 200 samples" in text
        assert code == 0 and "mine: PASS (2 checks)" in text
    elif flaw == "scalar":
        assert code == 1 and "FAIL  scalar" in out and "'eval':" in text and "'weight':" in text
    else:
        assert code == 1 and "raised ZeroDivisionError: float division by zero (sample at" in text


def test_cli_polarized_variant_checks_the_unpolarized_part(capsys):
    code = main(["check", "roughconductor", "--variant", "llvm_ad_mono_polarized", "--quick",
                 "--only", "weight", "--only", "furnace", "--only", "reciprocity"])
    text = capsys.readouterr().out
    assert code == 0 and "on the unpolarized part (Mueller element [0, 0]" in text
    assert "roughconductor: PASS (3 checks)" in text
