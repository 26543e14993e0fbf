"""The plugins in the scenes Mitsuba users build: what already works stays so.

Every plugin under direct, path, prb, prb_basic, volpath, volpathmis, ptracer and the
projective integrators, ptracer agreeing with path, the ``moment`` integrator, delta lights
(point, spot, directional), meshes with and without UVs, a scene from XML rendering as the
same scene from a dict, ``dr.freeze``.

The scenes put several spheres on a grid seen face-on by a distant camera, so that each
sphere fills one block of pixels (``checks.blocks``) and one render covers many cases;
``test_scenes_lobes.py`` raises and removes lobes in them.
"""
import gc

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

import mitsuba_brdfs
from mitsuba_brdfs.bsdf_xml import dict_to_xml
from checks import (CELL, DIRECTIONAL, DIST, FACTS, SEED, SPACING, SPOT, SPP, blocks,  # noqa: F401
                    check_declared, fov, grid, grid_scene, one_scene_at_a_time, render, rendered)

PLUGINS = sorted(mitsuba_brdfs.plugin_models())

pytestmark = pytest.mark.usefixtures("one_scene_at_a_time")


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


#: non-default parameters of every plugin (``FACTS.non_default``): floats, colours,
#: integers and load-time choices
XML_PARAMS = {p: FACTS[p].non_default for p in PLUGINS}


def as_dict(params):
    return {k: {"type": "rgb", "value": list(v)} if isinstance(v, tuple) else v
            for k, v in params.items()}


def as_xml(plugin, params):
    return dict_to_xml({"type": plugin, **as_dict(params)})


def test_xml_scene_renders_as_dict_scene():
    """The same scene written in XML and as a dict: the same image, pixel for pixel."""
    for p in PLUGINS:
        check_declared(p, "non_default")
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
                          "bsdf": {"type": name, FACTS[name].colour: tex}}
        return d

    assert len(mi.load_dict(scene(1200), optimize=False).shapes()) == 1200
    with pytest.raises(RuntimeError, match=r"lambert: parameter 'reflectance' must be a reflectance"):
        mi.load_dict(scene(600, bad_at=598), optimize=False)
