"""A new model is one file: a copy of ``models/lambert.py`` under another name is a model
the whole package knows.

The source tree is copied to a temporary folder, ``lambert2.py`` is written beside
``lambert.py`` with only its names changed, and the copy is run in fresh processes (its
folder first on the path): the suite collects without error and runs the generic tests on
the new model, and what cannot be generic (its float64 reference, its committed manual
page) fails saying what to add; ``check lambert2`` passes; the property table, the catalog,
the speed study and the manual list it. Nothing is written into the package.
"""
import os
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
NEW = "lambert2"

#: the tests that must fail for a model that adds nothing outside its file, and what their
#: messages say to do
NOT_GENERIC = {
    "test_layout.py::test_every_model_has_a_float64_reference[lambert2]":
        "tests/reference.py has no float64 reference of 'lambert2'",
    "test_hard_cases.py::test_opposite_grazing_pairs_match_float64[lambert2]":
        "tests/reference.py has no float64 reference of 'lambert2'",
    "test_models.py::test_eval_matches_float64[lambert2]":
        "tests/reference.py has no float64 reference of 'lambert2'",
    "test_models.py::test_eval_matches_float64[lambert2-reflectance=1.0]":
        "tests/reference.py has no float64 reference of 'lambert2'",
    "test_manual.py::test_page_matches_docstring[lambert2]":
        "docs/plugins/lambert2.md is missing: run `python -m mitsuba_brdfs manual",
}

pytestmark = pytest.mark.slow  # a copy of the tree and two dozen tests in a fresh process


def renamed(source):
    """``models/lambert.py`` with its names changed: plugin, class, the docstring's examples."""
    text = source
    for old, new in (('@bsdf_plugin("lambert")', f'@bsdf_plugin("{NEW}")'),
                     ("class Lambert(", "class Lambert2("), ('"Lambert"', '"Lambert2"'),
                     ("(``lambert``)", f"(``{NEW}``)"), ('type="lambert"', f'type="{NEW}"'),
                     ("'type': 'lambert'", f"'type': '{NEW}'")):
        assert old in text, old
        text = text.replace(old, new)
    return text


@pytest.fixture(scope="module")
def tree(tmp_path_factory):
    """The copy of the source tree, with the new model."""
    root = tmp_path_factory.mktemp("tree")
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", ".pytest_cache")
    for name in ("mitsuba_brdfs", "scenes", "tests", "docs"):
        shutil.copytree(os.path.join(ROOT, name), root / name, ignore=ignore)
    for name in ("README.md", "pyproject.toml"):
        shutil.copy(os.path.join(ROOT, name), root / name)
    models = root / "mitsuba_brdfs" / "models"
    (models / f"{NEW}.py").write_text(renamed((models / "lambert.py").read_text()))
    return root


def run(tree, *args, timeout=900):
    """``python args`` in the copy, which comes first on the path."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    return subprocess.run([sys.executable, *args], cwd=tree, env=env, capture_output=True,
                          text=True, timeout=timeout)


def test_the_suite_runs_the_generic_tests_on_a_copy_of_lambert(tree):
    report = tree / "report.xml"
    out = run(tree, "-m", "pytest", "-p", "no:cacheprovider", "-q", "-k", NEW,
              f"--junitxml={report}")
    assert out.returncode in (0, 1) and "error" not in out.stdout.splitlines()[-1], \
        out.stdout[-3000:] + out.stderr[-3000:]
    passed, failed = [], {}
    for case in ET.parse(report).getroot().iter("testcase"):
        name = f"{case.get('classname').split('.')[-1]}.py::{case.get('name')}"
        problem = case.find("failure") if case.find("failure") is not None else case.find("error")
        if problem is not None:
            failed[name] = problem.get("message", "") + (problem.text or "")
        elif case.find("skipped") is None:
            passed.append(name)
    assert all(NEW in name for name in passed + list(failed))
    assert set(failed) == set(NOT_GENERIC), {k: v[:300] for k, v in failed.items()}
    for name, says in NOT_GENERIC.items():
        assert says in failed[name], failed[name][:1000]
    assert len(passed) >= 30, passed


def test_check_passes_and_every_table_lists_it(tree):
    out = run(tree, "-m", "mitsuba_brdfs", "check", NEW)
    assert out.returncode == 0 and f"{NEW}: PASS" in out.stdout, out.stdout + out.stderr
    script = f"""
import mitsuba as mi
mi.set_variant("llvm_ad_rgb")
import mitsuba_brdfs
from mitsuba_brdfs import manual, properties
from mitsuba_brdfs.bench import speed, study
from mitsuba_brdfs.figures import catalog
assert mitsuba_brdfs.__file__.startswith({str(tree)!r}), mitsuba_brdfs.__file__
assert [c[1] for c in properties.CONFIGS if c[0] == "{NEW}"] == ["{NEW}"]
assert [e[0] for e in catalog.available(note=print)].count("{NEW}") == 1
assert "{NEW}" in [k for k, *_ in speed.CPP_PAIRS] and "{NEW}" in study.expected_models()
assert "[`{NEW}`]({NEW}.md)" in manual.overview()
print("listed")
"""
    out = run(tree, "-c", script)
    assert out.returncode == 0 and "listed" in out.stdout, out.stdout + out.stderr
