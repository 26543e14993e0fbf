"""The package's layout: ``import mitsuba_brdfs`` loads the library alone (not even NumPy,
which Mitsuba does not need either), and no import runs in a circle or from the library up
into the tools."""
import ast
import os
import re
import subprocess
import sys

import pytest

import mitsuba_brdfs

PACKAGE = os.path.dirname(os.path.abspath(mitsuba_brdfs.__file__))
ROOT = os.path.dirname(PACKAGE)


def test_import_loads_neither_tools_nor_their_libraries():
    code = ("import sys, mitsuba as mi; mi.set_variant('llvm_ad_rgb'); import mitsuba_brdfs; "
            "print(' '.join(sys.modules))")
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    loaded = set(r.stdout.split())
    assert "mitsuba_brdfs.models.ashikhmin_shirley" in loaded  # the library itself
    ours = {m.split(".")[1] for m in loaded if m.startswith("mitsuba_brdfs.")}
    assert ours == {"core", "models"}, ours
    for heavy in ("numpy", "matplotlib", "tqdm", "PIL", "scipy", "OpenEXR", "mitsuba.chi2"):
        assert heavy not in loaded, heavy


#: loads, renders and updates every plugin (a bitmap texture with a to_uv transform, the
#: Oren-Nayar table, an update refused), then prints the modules loaded
_USE_EVERY_PLUGIN = """
import sys
import mitsuba as mi
mi.set_variant(sys.argv[1])
import mitsuba_brdfs
assert mitsuba_brdfs.plugin_models()
bitmap = {"type": "bitmap", "bitmap": mi.Bitmap(mi.TensorXf([0.25] * 12, shape=(2, 2, 3))),
          "to_uv": mi.ScalarTransform4f().scale([2, 3, 1])}
bsdfs = [{"type": name} for name in mitsuba_brdfs.plugin_models()]
bsdfs.append({"type": "oren_nayar", "lut_resolution": 8, "reflectance": bitmap})
sensor = {"type": "perspective", "to_world": mi.ScalarTransform4f().translate([0, 0, -4]),
          "film": {"type": "hdrfilm", "width": 4, "height": 4}}
for bsdf in bsdfs:
    scene = mi.load_dict({"type": "scene", "integrator": {"type": "path"}, "sensor": sensor,
                          "ball": {"type": "sphere", "bsdf": bsdf}, "env": {"type": "constant"}})
    mi.render(scene, spp=1)
params = mi.traverse(scene)
params["ball.bsdf.reflectance.data"] = mi.TensorXf([2.0] * 12, shape=(2, 2, 3))
try:
    params.update()
except mitsuba_brdfs.ParameterError:
    pass
else:
    raise AssertionError("a reflectance of 2 was accepted")
print(" ".join(sys.modules))
"""


@pytest.mark.parametrize("variant", ["llvm_ad_rgb", "scalar_rgb"])
def test_plugins_need_no_numpy(variant):
    """Loading, rendering and updating the plugins (range checks included) loads no NumPy:
    a user of the plugins pays for Mitsuba alone."""
    r = subprocess.run([sys.executable, "-c", _USE_EVERY_PLUGIN, variant], cwd=ROOT,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    loaded = set(r.stdout.split())
    assert "mitsuba_brdfs.models.oren_nayar" in loaded
    assert "numpy" not in loaded


def _imports():
    """module -> the package's modules it imports, at the top or inside functions."""
    modules = {}
    for folder, _, files in os.walk(PACKAGE):
        for f in files:
            if f.endswith(".py"):
                path = os.path.join(folder, f)
                name = os.path.relpath(path, ROOT)[:-3].replace(os.sep, ".")
                modules[name.removesuffix(".__init__")] = path
    graph = {}
    for name, path in modules.items():
        package = name if path.endswith("__init__.py") else name.rpartition(".")[0]
        deps = set()
        for node in ast.walk(ast.parse(open(path).read())):
            if isinstance(node, ast.Import):
                deps.update(a.name for a in node.names)
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    base = ".".join(package.split(".")[:len(package.split(".")) - node.level + 1]
                                    + ([node.module] if node.module else []))
                deps.update(f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base
                            for a in node.names)
        graph[name] = {d for d in deps if d in modules and d != name}
    return graph


def test_the_library_imports_only_the_library():
    library = ("mitsuba_brdfs.core", "mitsuba_brdfs.models")
    for name, deps in _imports().items():
        if name == "mitsuba_brdfs" or name.startswith(library):
            assert all(d.startswith(library) for d in deps), (name, deps)


def test_no_modules_import_each_other():
    graph = _imports()
    done, path = set(), []

    def visit(m):
        assert m not in path, " -> ".join(path[path.index(m):] + [m])
        if m in done:
            return
        path.append(m)
        for d in sorted(graph[m]):
            visit(d)
        path.pop()
        done.add(m)

    for m in sorted(graph):
        visit(m)


def test_every_package_is_in_the_wheel():
    """pyproject.toml names the packages one by one (the scenes' and the examples' folders
    are mapped into the package): a new subpackage must be added there, or the wheel leaves
    it out."""
    tomllib = pytest.importorskip("tomllib")  # Python >= 3.11
    with open(os.path.join(ROOT, "pyproject.toml"), "rb") as f:
        setuptools = tomllib.load(f)["tool"]["setuptools"]
    # a folder with code (__init__.py) or data files (the explorer's static/): a package,
    # or setuptools warns at every install that it "would be ignored"
    found = {os.path.relpath(folder, ROOT).replace(os.sep, ".")
             for folder, _, files in os.walk(PACKAGE)
             if "__pycache__" not in folder and files}
    # (each folder of examples/ a package of its own: as package data of its parent
    # setuptools warns that it "would be ignored")
    examples = {"mitsuba_brdfs.examples"} | {
        f"mitsuba_brdfs.examples.{d}" for d in os.listdir(os.path.join(ROOT, "examples"))
        if os.path.isdir(os.path.join(ROOT, "examples", d)) and not d.startswith((".", "_"))}
    assert set(setuptools["packages"]) == found | {"mitsuba_brdfs.scenes"} | examples
    assert setuptools["package-dir"] == {"mitsuba_brdfs.scenes": "scenes",
                                         "mitsuba_brdfs.examples": "examples"}
    assert os.path.isfile(os.path.join(ROOT, "scenes", "as_sphere.xml"))
    assert os.path.isfile(os.path.join(ROOT, "examples", "mydiffuse", "mydiffuse.py"))


def test_the_licence_and_the_presets_notice_ship():
    """LICENSE holds the package's BSD-3-Clause licence (pyproject's SPDX expression), and
    the notice of the third-party data the package redistributes: the licence that the
    presets' CSV header names (the BRDF benchmark's), at the commit it names.
    ``test_installed.py`` finds it in the wheel."""
    tomllib = pytest.importorskip("tomllib")
    with open(os.path.join(ROOT, "pyproject.toml"), "rb") as f:
        project = tomllib.load(f)["project"]
    assert project["license"] == "BSD-3-Clause" and project["license-files"] == ["LICENSE"]
    text = open(os.path.join(ROOT, "LICENSE")).read()
    assert text.startswith("BSD 3-Clause License\n")
    assert "Redistribution and use in source and binary forms" in text
    with open(os.path.join(PACKAGE, "presets", "ngan2005.csv")) as f:
        header = "".join(line[2:] for line in f if line.startswith("# "))
    commit = re.search(r"commit ([0-9a-f]{40})", header).group(1)
    holder = re.search(r"Copyright \(c\) (\d{4} [^<]+<[^>]+>)", header).group(1)
    notice = text.split("Third-party notices")[1]
    assert commit in notice and f"Copyright (c) {holder}" in notice
    assert "github.com/bsdfbenchmark/bbm" in notice and "ngan2005.csv" in notice
