"""The package's import graph, the test suite's own layout, and the model registry every
per-model list follows.

- The package's modules import each other without circles, in at most ``MAX_FLOORS``
  floors, and no module imports a command (``__main__.COMMANDS``) or ``__main__``: the
  commands stand side by side on the library, and what two commands share lives in a
  library module (``spec``, ``messages``, ``validate``, ...); ``core/`` imports only
  ``core/``, ``models/`` only ``core/`` and ``models/``.

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

import mitsuba_brdfs
import reference
from checks import check_declared
from mitsuba_brdfs import plugin_models
from mitsuba_brdfs.__main__ import COMMANDS
from mitsuba_brdfs.bench import study
from mitsuba_brdfs.core.facts import Facts
from mitsuba_brdfs.models import module_of

#: what every model declares (the other fields of ``Facts`` are for the models they fit)
REQUIRED = ("colour", "differentiable", "non_default", "edges", "float64", "zero_lobes",
            "albedo", "properties", "catalog", "cpp")

TESTS = os.path.dirname(os.path.abspath(__file__))

#: the modules of tests/ that tests may import (none is collected by pytest)
HELPERS = {"checks", "reference", "phong_family", "cmdline", "explore_page", "user_bsdf"}


#: the longest chain of imports the package may have (a module that imports none of the
#: package's modules is on floor 1)
MAX_FLOORS = 8

#: (importer, command) imports waiting for a library module, left out of the floors too
#: (none: every library module imports only the library)
PENDING = set()


def package_modules(root=os.path.dirname(os.path.abspath(mitsuba_brdfs.__file__)),
                    name="mitsuba_brdfs"):
    """{dotted module name: file} of the package's modules (its folders with an
    ``__init__.py``: not the data folders)."""
    out = {}
    for folder, dirs, files in os.walk(root):
        if "__init__.py" not in files:
            dirs[:] = []
            continue
        dirs[:] = [d for d in dirs if not d.startswith((".", "__"))]
        rel = os.path.relpath(folder, root)
        base = ".".join([name] + ([] if rel == "." else rel.split(os.sep)))
        for f in files:
            if f.endswith(".py"):
                out[base if f == "__init__.py" else f"{base}.{f[:-3]}"] = os.path.join(folder, f)
    return out


def import_graph(modules=None):
    """{module: the package's modules it imports}, of ``modules`` (default: the package's):
    every ``import`` and ``from ... import`` of its file, at the top or inside a function
    (a lazy import is a dependency too). ``from . import x`` imports the module ``x`` if
    there is one, else the package's ``__init__``; a module imported by name at run time
    (``importlib``: ``__main__``'s commands, the models) is no arrow."""
    modules = modules or package_modules()

    def known(name):
        while name and name not in modules:
            name = name.rpartition(".")[0]
        return name

    graph = {}
    for module, path in modules.items():
        tree = ast.parse(open(path).read(), path)
        package = module if path.endswith("__init__.py") else module.rpartition(".")[0]
        found = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                found |= {known(a.name) for a in node.names}
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    parts = package.split(".")
                    base = ".".join(parts[:len(parts) - node.level + 1])
                    base = f"{base}.{node.module}" if node.module else base
                else:
                    base = node.module
                for a in node.names:
                    sub = f"{base}.{a.name}"
                    found.add(sub if sub in modules else known(base))
        graph[module] = {m for m in found if m and m != module}
    return graph


def floors(graph):
    """{module: its floor}: 1 + the highest floor among the modules it imports (1 for a
    module that imports none of the package's); a circle is an AssertionError naming it."""
    out, path = {}, []

    def floor(m):
        if m in out:
            return out[m]
        assert m not in path, f"import circle: {' -> '.join(path[path.index(m):] + [m])}"
        path.append(m)
        out[m] = 1 + max((floor(d) for d in graph[m]), default=0)
        path.pop()
        return out[m]

    for m in sorted(graph):
        floor(m)
    return out


def chain(graph, levels, module):
    """The longest chain of imports from ``module`` down, for messages."""
    out = [module]
    while graph[out[-1]]:
        out.append(max(sorted(graph[out[-1]]), key=levels.get))
    return " -> ".join(out)


def test_the_package_imports_without_circles_in_few_floors():
    graph = import_graph()
    floors(graph)  # raises on a circle
    for importer, command in PENDING:
        graph[importer].discard(command)
    levels = floors(graph)
    top = max(levels, key=levels.get)
    assert levels[top] <= MAX_FLOORS, (f"{levels[top]} floors: {chain(graph, levels, top)}")


def test_no_module_imports_a_command():
    """Commands stand side by side: none imports another, no library module imports one,
    and nothing imports ``__main__`` (which dispatches by name)."""
    graph = import_graph()
    commands = {module for module, _ in COMMANDS.values()} | {"mitsuba_brdfs.__main__"}
    assert commands <= set(graph), commands - set(graph)
    arrows = {(m, d) for m, deps in graph.items() for d in deps if d in commands}
    assert arrows <= PENDING, f"imports of commands: {sorted(arrows - PENDING)}"
    assert PENDING <= arrows, f"no longer imported, take it out of PENDING: {PENDING - arrows}"


def test_core_and_models_import_only_below_them():
    graph = import_graph()
    allowed = {"mitsuba_brdfs.core": ("mitsuba_brdfs.core",),
               "mitsuba_brdfs.models": ("mitsuba_brdfs.core", "mitsuba_brdfs.models")}
    for module, deps in graph.items():
        for prefix, below in allowed.items():
            if module == prefix or module.startswith(prefix + "."):
                wrong = {d for d in deps if not d.startswith(below)}
                assert not wrong, f"{module} imports {sorted(wrong)}"


def test_the_import_graph_sees_every_kind_of_import(tmp_path):
    """The graph reads relative, absolute and lazy imports, and finds circles."""
    pkg = tmp_path / "p"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "data").mkdir()
    (pkg / "__init__.py").write_text("from .a import x\n")
    (pkg / "a.py").write_text("x = 1\n")
    (pkg / "b.py").write_text("def f():\n    from . import a\n    import p.sub.c\n")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "sub" / "c.py").write_text("from .. import b\nfrom ..a import x\n")
    (pkg / "data" / "d.py").write_text("import p.b\n")  # not a package: not a module
    modules = package_modules(str(pkg), "p")
    assert set(modules) == {"p", "p.a", "p.b", "p.sub", "p.sub.c"}
    graph = import_graph(modules)
    assert graph == {"p": {"p.a"}, "p.a": set(), "p.b": {"p.a", "p.sub.c"}, "p.sub": set(),
                     "p.sub.c": {"p.b", "p.a"}}
    with pytest.raises(AssertionError, match="import circle: p.b -> p.sub.c -> p.b"):
        floors(graph)
    del graph["p.sub.c"]
    graph["p.b"] = {"p.a"}
    assert floors(graph) == {"p": 2, "p.a": 1, "p.b": 2, "p.sub": 1}


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
