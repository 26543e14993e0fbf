"""The plugins in the scenes Mitsuba users build.

- A lobe that a zero colour removes comes back when ``params.update()`` raises the colour,
  inside every wrapper (none, twosided, blendbsdf, mask, normalmap, bumpmap): the render
  equals that of the scene loaded with the raised value, and the other way round.
- Absent lobes are not traced, measured: the IR of a metal (no diffuse lobe) and of a
  black ``lambert`` is smaller than with the lobe, and grows when the lobe is raised; with
  a gradient enabled the lobe is traced, and the gradient at black is not zero (prb).
- What already works stays so: every plugin under direct, path, prb, prb_basic, volpath,
  volpathmis, ptracer and the projective integrators, ptracer agreeing with path, the
  ``moment`` integrator, delta lights (point, spot, directional), meshes with and without
  UVs, a scene from XML rendering as the same scene from a dict, ``dr.freeze``.

The scenes put several spheres on a grid seen face-on by a distant camera, so that each
sphere fills one block of pixels (``blocks``) and one render covers many cases.
"""
import copy
import gc
import math

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

import mitsuba_brdfs
from mitsuba_brdfs.timing import bsdf_instructions, kernel_stats

PLUGINS = sorted(mitsuba_brdfs.plugin_models())
T = mi.ScalarTransform4f

#: pixels per grid cell, samples per pixel, seed, distance between sphere centres
CELL, SPP, SEED, SPACING = 16, 4, 7, 2.5
POINT = {"type": "point", "position": [3, 4, 12], "intensity": {"type": "rgb", "value": 200}}
SPOT = {"type": "spot", "to_world": T().look_at(origin=[3, 4, 12], target=[0, 0, 0], up=[0, 1, 0]),
        "cutoff_angle": 30, "intensity": {"type": "rgb", "value": 200}}
DIRECTIONAL = {"type": "directional", "direction": [-0.3, -0.4, -1],
               "irradiance": {"type": "rgb", "value": 1.5}}


# -- grid scenes ------------------------------------------------------------------------------

def grid(names, cols):
    """(cols, rows) of a grid holding ``names``, and each name's (column, row)."""
    rows = math.ceil(len(names) / cols)
    return cols, rows, {n: (i % cols, i // cols) for i, n in enumerate(names)}


#: distance of the camera to the grid
DIST = 40.0


def fov(cols):
    """The horizontal field of view that shows ``cols`` cells of the grid."""
    return 2 * math.degrees(math.atan(cols * SPACING / 2 / DIST))


def grid_scene(cells, cols=3, integrator=None, light=POINT, env=0.2, optimize=True,
               shapes=None):
    """A scene with one sphere per entry of ``cells`` (name -> BSDF dict), on a grid of
    ``cols`` columns facing the camera; each sphere fills one CELL x CELL block.
    ``shapes`` (name -> shape dict without position) replaces the spheres' shapes."""
    names = list(cells)
    cols, rows, where = grid(names, cols)
    scene = {
        "type": "scene",
        "integrator": integrator or {"type": "path", "max_depth": 3},
        "sensor": {"type": "perspective", "fov": fov(cols), "fov_axis": "x",
                   "to_world": T().look_at(origin=[0, 0, DIST], target=[0, 0, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": cols * CELL, "height": rows * CELL,
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": SPP}},
        "light": light,
    }
    if env:
        scene["env"] = {"type": "constant", "radiance": {"type": "rgb", "value": env}}
    for name, bsdf in cells.items():
        c, r = where[name]
        centre = [(c + 0.5 - cols / 2) * SPACING, (rows / 2 - r - 0.5) * SPACING, 0]
        shape = dict((shapes or {}).get(name, {"type": "sphere", "radius": 1.0}))
        shape["to_world"] = T().translate(centre) @ shape.get("to_world", T())
        scene[name] = {**shape, "bsdf": bsdf}
    return mi.load_dict(scene, optimize=optimize)


def blocks(img, names, cols=3):
    """name -> the block of pixels of the sphere ``name`` in a grid_scene render."""
    img = np.asarray(img, dtype=np.float64)
    _, _, where = grid(list(names), cols)
    return {n: img[r * CELL:(r + 1) * CELL, c * CELL:(c + 1) * CELL] for n, (c, r) in where.items()}


def render(scene, params=None, spp=SPP, seed=SEED, **kw):
    return np.array(mi.render(scene, params, spp=spp, seed=seed, **kw), dtype=np.float64)


def rendered(cells, spp=SPP, seed=SEED, **kw):
    """The image of ``grid_scene(cells, **kw)``, the scene dropped before returning."""
    scene = grid_scene(cells, **kw)
    img = render(scene, spp=spp, seed=seed)
    del scene
    gc.collect()
    return img


@pytest.fixture(autouse=True)
def _one_scene_at_a_time():
    """A render traces the methods of every live BSDF: the scenes of earlier tests must be
    gone (kernel sizes are measured, and compiling less is faster). Tests that hold
    several scenes drop each (``del``, then a collection) before the next renders."""
    gc.collect()
    yield
    gc.collect()


# -- 1. a zero lobe raised through traverse, in every wrapper ------------------------------------

WRAPPERS = ("none", "twosided", "blendbsdf", "mask", "normalmap", "bumpmap")


@pytest.fixture(scope="module")
def flat_normalmap(tmp_path_factory):
    """A normal map of the unperturbed normal, (0.5, 0.5, 1) in the map's encoding."""
    path = tmp_path_factory.mktemp("normalmap") / "flat.exr"
    mi.Bitmap(np.tile(np.array([0.5, 0.5, 1.0], np.float32), (2, 2, 1))).write(str(path))
    return str(path)


def wrapped(kind, bsdf, normalmap):
    """``bsdf`` (a dict, copied) inside the wrapper ``kind``."""
    b = copy.deepcopy(bsdf)
    if kind == "none":
        return b
    if kind == "twosided":
        return {"type": "twosided", "bsdf": b}
    if kind == "blendbsdf":
        return {"type": "blendbsdf", "weight": 0.6, "bsdf_0": b,
                "bsdf_1": {"type": "diffuse", "reflectance": 0.2}}
    if kind == "mask":
        return {"type": "mask", "opacity": 0.7, "bsdf": b}
    if kind == "normalmap":
        return {"type": "normalmap", "bsdf": b,
                "normalmap": {"type": "bitmap", "filename": normalmap, "raw": True}}
    if kind == "bumpmap":
        return {"type": "bumpmap", "bsdf": b, "arbitrary": {"type": "uniform", "value": 0.3}}
    raise ValueError(kind)


def rgb(v):
    return {"type": "rgb", "value": [float(v)] * 3}


def value(param, v):
    """A colour as <rgb>, a weight (cook_torrance's k) as a float."""
    return float(v) if param == "k" else rgb(v)


#: (plugin, parameter, value that removes a lobe, value that gives it back, other parameters)
ZERO_LOBES = [
    ("lambert", "reflectance", 0, 0.5, {}),
    ("oren_nayar", "reflectance", 0, 0.5, {}),
    ("ashikhmin_shirley", "diffuse_reflectance", 0, 0.5, {}),
    ("phong", "diffuse_reflectance", 0, 0.5, {}),
    ("phong", "specular_reflectance", 0, 0.5, {}),
    ("blinn_phong", "diffuse_reflectance", 0, 0.5, {}),
    ("blinn_phong", "specular_reflectance", 0, 0.5, {}),
    ("torrance_sparrow", "diffuse_reflectance", 0, 0.5, {}),
    ("torrance_sparrow", "specular_reflectance", 0, 0.5, {}),
    ("ward", "diffuse_reflectance", 0, 0.5, {}),
    ("ward", "specular_reflectance", 0, 0.5, {}),
    ("cook_torrance", "diffuse_reflectance", 0, 0.5, {}),
    ("cook_torrance", "specular_reflectance", 0, 0.5, {}),
    ("cook_torrance", "k", 0, 0.5, {}),   # no diffuse lobe
    ("cook_torrance", "k", 1, 0.5, {}),   # no specular lobe
    ("toon", "diffuse_reflectance", 0, 0.5, {"diffuse_shade": rgb(0)}),
    ("toon", "specular_reflectance", 0, 0.5, {"specular_shade": rgb(0)}),
]


def case_id(case):
    return f"{case[0]}-{case[1]}-{case[2]}"


def wrapper_scene(state, normalmap):
    """Every case of ZERO_LOBES (a row) in every wrapper (a column), with each case's
    parameter at ``state`` ("zero" or "raised"); each sphere holds its own instance (the
    loader would otherwise merge identical BSDFs into one)."""
    cells = {}
    for case in ZERO_LOBES:
        plugin, param, zero, raised, extra = case
        bsdf = {"type": plugin, param: value(param, zero if state == "zero" else raised), **extra}
        for w in WRAPPERS:
            cells[f"{case_id(case)}_{w}"] = wrapped(w, bsdf, normalmap)
    return grid_scene(cells, cols=len(WRAPPERS), optimize=False)


def case_keys(params, case):
    """The traverse keys of a case's parameter, one per wrapper (not the blend's partner)."""
    return [k for k in params.keys() if k.startswith(f"{case_id(case)}_")
            and k.endswith(f".{case[1]}.value") and ".bsdf_1." not in k]


def set_cases(params, state):
    for case in ZERO_LOBES:
        v = case[2] if state == "zero" else case[3]
        for k in case_keys(params, case):
            params[k] = type(params[k])(float(v))
    params.update()


def lobes_present(scene, case):
    bsdf = next(s.bsdf() for s in scene.shapes() if s.id() == f"{case_id(case)}_none")
    return sum(bsdf._present)


def compare_blocks(got, want, names, what):
    """One line per block where ``got`` differs from ``want``."""
    got, want = blocks(got, names, len(WRAPPERS)), blocks(want, names, len(WRAPPERS))
    return [f"{n}: {what}: mean {got[n].mean():.5f} vs {want[n].mean():.5f}" for n in names
            if not np.allclose(got[n], want[n], rtol=1e-5, atol=1e-6)]


def load_render_update_render(state, other, normalmap):
    """Load the wrapper scene at ``state``, render, set every case to ``other`` through
    mi.traverse, render again: (scene facts, image before, image after).

    One scene is alive at a time: a render traces the methods of every live BSDF.
    """
    scene = wrapper_scene(state, normalmap)
    present = {case_id(c): lobes_present(scene, c) for c in ZERO_LOBES}
    before = render(scene)
    params = mi.traverse(scene)
    keys = {case_id(c): len(case_keys(params, c)) for c in ZERO_LOBES}
    set_cases(params, other)
    after = render(scene)
    del scene, params
    gc.collect()
    return {"present": present, "keys": keys}, before, after


def test_zero_lobe_raised_through_traverse(flat_normalmap):
    """Every case of ZERO_LOBES in every wrapper, loaded with the lobe removed, then raised
    through mi.traverse: the render equals the scene loaded with the raised values; and
    the scene loaded raised, lowered through mi.traverse, renders as the one loaded with
    the lobes removed (same seed). Before the flags were fixed at build time, lambert in
    twosided rendered black after the update."""
    assert {c[0] for c in ZERO_LOBES} == set(PLUGINS)
    names = [f"{case_id(c)}_{w}" for c in ZERO_LOBES for w in WRAPPERS]
    facts_low, img_low, img_raised = load_render_update_render("zero", "raised", flat_normalmap)
    facts_high, img_high, img_lowered = load_render_update_render("raised", "zero", flat_normalmap)
    for c in map(case_id, ZERO_LOBES):
        assert facts_low["present"][c] == facts_high["present"][c] - 1, \
            f"{c}: the value does not remove a lobe"
        # the keys reach through every wrapper
        assert facts_low["keys"][c] == len(WRAPPERS), (c, facts_low["keys"][c])
    assert np.isfinite(img_low).all() and np.isfinite(img_high).all()
    b_low, b_high = blocks(img_low, names, len(WRAPPERS)), blocks(img_high, names, len(WRAPPERS))
    dark = [n for n in names if not np.abs(b_low[n] - b_high[n]).max() > 1e-3]
    assert not dark, f"the lobe does not show in {dark}"
    failures = compare_blocks(img_raised, img_high, names, "raised")
    failures += compare_blocks(img_lowered, img_low, names, "lowered")
    assert not failures, "\n".join(failures)


# -- 2. absent lobes are not traced, and measured ------------------------------------------------

def bsdf_sizes(plugin, param, v, raise_to=None):
    """IR instructions of the BSDF's own sample and eval_pdf (``bsdf_instructions``), loaded
    with ``param = v``; with ``raise_to``, after setting it to that value through traverse."""
    gc.collect()
    bsdf = mi.load_dict({"type": plugin, param: v})
    params = mi.traverse(bsdf)
    if raise_to is not None:
        params[f"{param}.value"] = mi.Float(raise_to)
        params.update()
    sizes = bsdf_instructions(bsdf)
    del bsdf, params
    gc.collect()
    return sizes


def render_ops(plugin, param, v, raise_to=None):
    """IR operations of the render kernel of a sphere of the plugin with ``param = v``;
    with ``raise_to``, of the same scene after setting it to that value through traverse.
    Nothing else is alive meanwhile (a render traces every live BSDF)."""
    gc.collect()
    scene = grid_scene({"ball": {"type": plugin, param: v}}, cols=1)
    params = mi.traverse(scene)
    if raise_to is not None:
        kernel_stats(scene, spp=2)
        params[f"ball.bsdf.{param}.value"] = mi.Float(raise_to)
        params.update()
    ops = kernel_stats(scene, spp=2)["ops_max"]
    del scene, params
    gc.collect()
    return ops


METALS = [("ashikhmin_shirley", "diffuse_reflectance"), ("lambert", "reflectance")]


@pytest.mark.parametrize("plugin,param", METALS)
def test_absent_lobe_is_not_traced(plugin, param):
    """The BSDF's own sample and eval_pdf kernels, and the render kernel: smaller without
    the lobe, the size of the two-lobe BSDF once the lobe is raised through traverse."""
    metal, full = bsdf_sizes(plugin, param, 0.0), bsdf_sizes(plugin, param, 0.5)
    raised = bsdf_sizes(plugin, param, 0.0, raise_to=0.5)
    for what in ("sample", "eval_pdf"):
        assert metal[what] < full[what], (what, metal, full)
        assert raised[what] == full[what], (what, raised, full)
    if plugin == "lambert":  # no lobe at all: nothing of the BSDF is traced
        assert metal == {"sample": 0, "eval_pdf": 0}

    ops_metal, ops_full = render_ops(plugin, param, 0.0), render_ops(plugin, param, 0.5)
    ops_raised = render_ops(plugin, param, 0.0, raise_to=0.5)
    assert ops_metal < ops_full, (ops_metal, ops_full)
    assert ops_raised == ops_full, (ops_raised, ops_full)


def test_gradient_at_black_is_not_zero():
    """prb: with the gradient of a zero colour enabled, the removed lobe is traced and the
    gradient of the image w.r.t. that colour is positive in every channel (an
    optimisation may start from black), also inside a wrapper."""
    cells = {"metal": {"type": "ashikhmin_shirley", "diffuse_reflectance": rgb(0)},
             "black": {"type": "lambert", "reflectance": rgb(0)},
             "wrapped": {"type": "twosided", "bsdf": {"type": "lambert",
                                                      "reflectance": rgb(0)}}}
    scene = grid_scene(cells, integrator={"type": "prb", "max_depth": 3}, optimize=False)
    params = mi.traverse(scene)
    keys = {"metal": "metal.bsdf.diffuse_reflectance.value",
            "black": "black.bsdf.reflectance.value",
            "wrapped": next(k for k in params.keys() if k.startswith("wrapped.") and k.endswith("reflectance.value"))}
    for k in keys.values():
        dr.enable_grad(params[k])
    params.update()
    img = mi.render(scene, params, spp=SPP, seed=SEED)
    dr.backward(dr.mean(img, axis=None))
    grads = {n: np.array(dr.grad(params[k]), dtype=np.float64) for n, k in keys.items()}
    for n, g in grads.items():
        assert np.isfinite(g).all() and (g > 0).all(), (n, g)


# -- 3. what already works ----------------------------------------------------------------------

INTEGRATORS = ["direct", "path", "prb", "prb_basic", "volpath", "volpathmis", "ptracer",
               "prb_projective", "direct_projective"]


def check_lit(img, names, cols=3, tag=""):
    """Every sphere's block is finite and lit."""
    for n, b in blocks(img, names, cols).items():
        assert np.isfinite(b).all(), (tag, n)
        assert b.mean() > 0.01, (tag, n, b.mean())


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_every_plugin_under_integrator(integrator):
    img = rendered({p: {"type": p} for p in PLUGINS}, integrator={"type": integrator})
    check_lit(img, PLUGINS, tag=integrator)


@pytest.mark.parametrize("light", ["spot", "directional"])
def test_every_plugin_under_delta_light(light):
    """Delta lights are reached only by emitter sampling, which needs exact flags (the point
    light is in every integrator test). Without the environment, only the light shows."""
    img = rendered({p: {"type": p} for p in PLUGINS}, light=SPOT if light == "spot" else DIRECTIONAL,
                   env=0)
    check_lit(img, PLUGINS, tag=light)


def test_ptracer_agrees_with_path():
    """Light tracing (Importance transport) and path tracing give the same image, up to
    Monte Carlo noise, for the diffuse-dominated models; Mitsuba's diffuse is the control."""
    cells = {"lambert": {"type": "lambert"}, "oren_nayar": {"type": "oren_nayar", "sigma": 0.5},
             "ashikhmin_shirley": {"type": "ashikhmin_shirley", "nu": 10.0, "nv": 30.0},
             "diffuse": {"type": "diffuse"}}
    means = {}
    for integrator in ("path", "ptracer"):
        img = rendered(cells, spp=1024, cols=4, integrator={"type": integrator, "max_depth": 2},
                       light=DIRECTIONAL, env=0)
        means[integrator] = {n: b.mean() for n, b in blocks(img, cells, cols=4).items()}
    for n in cells:
        assert means["path"][n] > 0.02, n
        assert abs(means["ptracer"][n] / means["path"][n] - 1) < 0.03, (n, means)


def test_moment_integrator():
    """``moment`` around path: its first moment is path's image (same samples), its second
    moment at least the square of the first, and above it where samples differ."""
    cells = {p: {"type": p} for p in PLUGINS}
    scene = grid_scene(cells, integrator={"type": "moment", "nested": {"type": "path", "max_depth": 3}})
    mi.render(scene, spp=SPP, seed=SEED)
    # the film holds both moments as XYZ (the second one: of each sample's XYZ values)
    layers = dict(scene.sensors()[0].film().bitmap().split())
    first = np.array(layers["nested"], dtype=np.float64)
    second = np.array(layers["m2_nested"], dtype=np.float64)
    first_rgb = np.array(layers["nested"].convert(mi.Bitmap.PixelFormat.RGB,
                                                  mi.Struct.Type.Float32, False), dtype=np.float64)
    del scene, layers
    gc.collect()
    img = rendered(cells)
    np.testing.assert_allclose(first_rgb, img, rtol=1e-4, atol=1e-5)
    assert np.isfinite(second).all()
    assert (second >= first ** 2 * (1 - 1e-4) - 1e-7).all()
    # and the spheres' highlights vary from sample to sample: the variance shows
    assert ((second - first ** 2) > 1e-3).any()
    check_lit(first_rgb, PLUGINS)


@pytest.fixture(scope="module")
def meshes_without_uv(tmp_path_factory):
    """A unit quad (two triangles, no texture coordinates, no normals) as OBJ and PLY."""
    d = tmp_path_factory.mktemp("meshes")
    verts = [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]
    obj = d / "quad.obj"
    obj.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in verts) + "f 1 2 3\nf 1 3 4\n")
    ply = d / "quad.ply"
    ply.write_text("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                   "property float z\nelement face 2\nproperty list uchar int vertex_indices\n"
                   "end_header\n" + "".join(f"{x} {y} {z}\n" for x, y, z in verts)
                   + "3 0 1 2\n3 0 2 3\n")
    return {"obj": str(obj), "ply": str(ply)}


def test_anisotropic_models_on_meshes_with_and_without_uv(meshes_without_uv):
    """A rectangle (with UVs) and OBJ / PLY quads without UVs: the anisotropic models,
    whose lobes follow the surface's u direction, render finite and lit on all of them."""
    aniso = {"ashikhmin_shirley": {"type": "ashikhmin_shirley", "nu": 10.0, "nv": 1000.0},
             "ward": {"type": "ward", "alpha_u": 0.05, "alpha_v": 0.4}}
    meshes = {"rectangle": {"type": "rectangle"},
              "obj": {"type": "obj", "filename": meshes_without_uv["obj"]},
              "ply": {"type": "ply", "filename": meshes_without_uv["ply"]}}
    cells, shapes = {}, {}
    for p, b in aniso.items():
        for m, s in meshes.items():
            cells[f"{p}-{m}"], shapes[f"{p}-{m}"] = b, s
    scene = grid_scene(cells, shapes=shapes, optimize=False)  # (no merging of the meshes)
    # the OBJ and PLY quads have no UVs
    assert sum(s.is_mesh() and not s.has_vertex_texcoords() for s in scene.shapes()) == 4
    img = render(scene)
    check_lit(img, cells)


#: non-default parameters of every plugin: floats, colours, integers and load-time choices
XML_PARAMS = {
    "ashikhmin_shirley": {"nu": 20.0, "nv": 200.0, "specular_reflectance": (0.3, 0.3, 0.2)},
    "blinn_phong": {"exponent": 60.0, "form": "modified"},
    "cook_torrance": {"distribution": "ggx", "roughness": 0.2, "f0": (0.9, 0.6, 0.5)},
    "lambert": {"reflectance": (0.8, 0.3, 0.1)},
    "oren_nayar": {"sigma": 0.4, "lut_resolution": 16},
    "phong": {"form": "modified", "diffuse_reflectance": (0.2, 0.5, 0.3)},
    "toon": {"smoothing": 0.05, "specular_model": "blinn"},
    "torrance_sparrow": {"eta": 1.8, "exponent": 50.0},
    "ward": {"alpha_u": 0.1, "alpha_v": 0.3, "specular_reflectance": (0.3, 0.2, 0.2)},
}


def as_dict(params):
    return {k: {"type": "rgb", "value": list(v)} if isinstance(v, tuple) else v
            for k, v in params.items()}


def as_xml(plugin, params):
    body = []
    for k, v in params.items():
        if isinstance(v, tuple):
            body.append(f'<rgb name="{k}" value="{", ".join(map(str, v))}"/>')
        elif isinstance(v, str):
            body.append(f'<string name="{k}" value="{v}"/>')
        elif isinstance(v, int):
            body.append(f'<integer name="{k}" value="{v}"/>')
        else:
            body.append(f'<float name="{k}" value="{v}"/>')
    return f'<bsdf type="{plugin}">{"".join(body)}</bsdf>'


def test_xml_scene_renders_as_dict_scene():
    """The same scene written in XML and as a dict: the same image, pixel for pixel."""
    assert set(XML_PARAMS) == set(PLUGINS)
    cells = {p: {"type": p, **as_dict(XML_PARAMS[p])} for p in PLUGINS}
    from_dict = grid_scene(cells)
    img_dict = render(from_dict)
    del from_dict
    gc.collect()
    # grid_scene's scene in XML
    cols, rows, where = grid(PLUGINS, 3)
    shapes = []
    for p in PLUGINS:
        c, r = where[p]
        x, y = (c + 0.5 - cols / 2) * SPACING, (rows / 2 - r - 0.5) * SPACING
        shapes.append(f'<shape type="sphere"><transform name="to_world"><translate x="{x}" y="{y}" z="0"/>'
                      f'</transform>{as_xml(p, XML_PARAMS[p])}</shape>')
    xml = f"""<scene version="3.0.0">
        <integrator type="path"><integer name="max_depth" value="3"/></integrator>
        <sensor type="perspective">
            <float name="fov" value="{fov(cols)!r}"/><string name="fov_axis" value="x"/>
            <transform name="to_world"><lookat origin="0, 0, {DIST}" target="0, 0, 0" up="0, 1, 0"/></transform>
            <film type="hdrfilm"><integer name="width" value="{cols * CELL}"/>
                <integer name="height" value="{rows * CELL}"/><rfilter type="box"/></film>
            <sampler type="independent"><integer name="sample_count" value="{SPP}"/></sampler>
        </sensor>
        <emitter type="point"><point name="position" x="3" y="4" z="12"/>
            <rgb name="intensity" value="200"/></emitter>
        <emitter type="constant"><rgb name="radiance" value="0.2"/></emitter>
        {"".join(shapes)}
    </scene>"""
    from_xml = mi.load_string(xml)
    img_xml = render(from_xml)
    check_lit(img_dict, PLUGINS)
    np.testing.assert_allclose(img_xml, img_dict, rtol=1e-5, atol=1e-6)


def test_frozen_render_equals_unfrozen():
    """A render function frozen with ``dr.freeze`` gives the unfrozen images, replaying
    its recording (fewer recordings than calls), also after a parameter update."""
    scene = grid_scene({p: {"type": p} for p in PLUGINS})

    @dr.freeze
    def frozen(scene, seed):
        return mi.render(scene, spp=SPP, seed=seed)

    params = mi.traverse(scene)
    calls = 0
    for seed in range(1, 6):
        if seed == 4:
            params["ward.bsdf.diffuse_reflectance.value"] = mi.Float(0.9)
            params["ashikhmin_shirley.bsdf.nu.value"] = mi.Float(300.0)
            params.update()
        got = np.array(frozen(scene, mi.UInt32(seed)), dtype=np.float64)
        calls += 1
        want = render(scene, seed=seed)
        np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-6, err_msg=f"seed {seed}")
    assert frozen.n_recordings < calls, (frozen.n_recordings, calls)


@pytest.mark.slow  # a stress test: 1,200 textured shapes loaded
def test_scene_with_hundreds_of_textured_materials_loads(tmp_path):
    """Mitsuba loads a scene's objects in parallel, and a thread waiting for a kernel runs
    other loading tasks nested on its stack: when every textured material checked its
    bitmap with a kernel inside its constructor, 800 of them ended in a RecursionError.
    Nested constructors leave their checks to the outermost one; a bad bitmap among
    hundreds still fails the load, naming its plugin and parameter."""
    from PIL import Image
    rng = np.random.default_rng(0)
    files = []
    for i in range(8):
        files.append(str(tmp_path / f"t{i}.png"))
        Image.fromarray((rng.random((4, 4, 3)) * 255).astype(np.uint8)).save(files[-1])
    bad = str(tmp_path / "bad.exr")
    mi.Bitmap(np.full((4, 4, 3), 2.0, np.float32)).write(bad)
    models = ["ashikhmin_shirley", "phong", "cook_torrance", "ward", "lambert", "toon"]

    def scene(n, bad_at=None):
        d = {"type": "scene"}
        for i in range(n):
            name = models[i % len(models)]
            tex = {"type": "bitmap", "filename": bad if i == bad_at else files[i % len(files)]}
            d[f"s{i}"] = {"type": "rectangle",
                          "to_world": mi.ScalarTransform4f().translate([i, 0, 0]),
                          "bsdf": {"type": name, ("reflectance" if name == "lambert"
                                                  else "diffuse_reflectance"): tex}}
        return d

    assert len(mi.load_dict(scene(1200), optimize=False).shapes()) == 1200
    with pytest.raises(RuntimeError, match=r"lambert: parameter 'reflectance' must be a reflectance"):
        mi.load_dict(scene(600, bad_at=598), optimize=False)
