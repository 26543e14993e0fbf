"""The test suite's own layout, and the model registry every per-model list follows.

- A test module imports no other test module and not ``conftest``: what tests share lives
  in the helper modules pytest does not collect (``HELPERS``), and conftest only sets up.
- Every model of the package (``mitsuba_brdfs.plugin_models()``, filled by the model
  modules themselves) declares in its module what the generic tests, tables and figures
  run of it (``FACTS``), has a float64 reference in ``reference.py``, and the performance
  study expects exactly those models: a new model is not silently left out.
"""
import ast
import os
import sys

import numpy as np
import pytest

import reference
from checks import check_declared
from mitsuba_brdfs import plugin_models
from mitsuba_brdfs.bench import study
from mitsuba_brdfs.core.facts import Facts
from mitsuba_brdfs.models import module_of

#: what every model declares (the other fields of ``Facts`` are for the models they fit)
REQUIRED = ("colour", "differentiable", "non_default", "edges", "float64", "zero_lobes",
            "albedo", "properties", "catalog", "cpp")

TESTS = os.path.dirname(os.path.abspath(__file__))

#: the modules of tests/ that tests may import (none is collected by pytest)
HELPERS = {"checks", "reference", "phong_family", "cmdline", "explore_page"}


def local_modules():
    return {f[:-3] for f in os.listdir(TESTS) if f.endswith(".py")}


def imported(path):
    """Top-level names of the modules a Python file imports."""
    tree = ast.parse(open(path).read(), path)
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
    return names


def test_tests_import_only_helper_modules():
    local = local_modules()
    assert HELPERS <= local
    bad = {}
    for name in sorted(local):
        wrong = (imported(os.path.join(TESTS, name + ".py")) & local) - HELPERS
        if wrong:
            bad[name] = sorted(wrong)
    assert not bad, f"test files importing test files or conftest: {bad}"
    # the helpers are not collected, and conftest exports nothing to import
    assert not any(h.startswith("test") for h in HELPERS)


@pytest.mark.parametrize("plugin", sorted(plugin_models()))
def test_every_model_declares_its_facts(plugin):
    """A model is one file: its module ends with ``FACTS = Facts(...)``, which the generic
    tests, the property table, the catalog and the benchmarks read."""
    facts = getattr(sys.modules[plugin_models()[plugin].__module__], "FACTS", None)
    assert isinstance(facts, Facts), (f"{module_of(plugin)} declares no FACTS: add "
                                      f"FACTS = Facts(...) (see mitsuba_brdfs/core/facts.py)")
    check_declared(plugin, *REQUIRED)


@pytest.mark.parametrize("plugin", sorted(plugin_models()))
def test_every_model_has_a_float64_reference(plugin):
    assert plugin in reference.REFERENCES, reference.missing(plugin)


def test_every_reference_is_a_model():
    assert set(reference.REFERENCES) <= set(plugin_models())


def test_references_take_wi_then_wo():
    """One argument order: (wi = viewer, wo = light). Models whose f is not symmetric in
    its directions show it: the one-sided Lambert is zero when only wo is below."""
    up, down = np.array([[0.0, 0.6, 0.8]]), np.array([[0.0, 0.6, -0.8]])
    for name in set(plugin_models()) & set(reference.REFERENCES):
        assert (reference.f(name, up, up) > 0).all(), name
    np.testing.assert_array_equal(reference.lambert(up, down, 0.5), 0)
    # Phong's original form divides by cos(theta_light): wo's cosine
    wi, wo = np.array([[0.0, 0.0, 1.0]]), np.array([[0.0, 0.6, 0.8]])
    spec, _ = reference.phong(wi, wo, 0.0, 1.0, 0.0, "original")
    np.testing.assert_allclose(spec, 1 / 0.8)


def test_the_study_expects_every_model():
    assert set(study.expected_models()) == set(plugin_models())
