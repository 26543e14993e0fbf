"""The range checks of ``core/params.py``: every texel of a bitmap in every variant, and the
messages of refused values.

A scalar variant computes what a bitmap returns from its stored array in one pass (bytes
decoded, luminance, the spectral variant's fitted spectra) and looks up through Mitsuba
only the texels that hold the extremes: the ranges it finds are those of the LLVM
variants, which look every texel up, for each storage layout; a single NaN or -2 anywhere
in a 512 x 256 image is refused, at load and from ``params.update()``; ward's
``alpha_u = 0`` never reaches ``eval``. A refused value is printed with the digits that
tell it from the range's end (1.0000001 is not 1), and an unbounded range says that
infinity is refused ([1, inf)).
"""
import math

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from PIL import Image

import mitsuba_brdfs
from checks import FACTS
from mitsuba_brdfs import manual
from mitsuba_brdfs.core import params as P
from mitsuba_brdfs.core import texture_ranges as T

W, H = 512, 256
#: an odd texel index, away from every stride a subset would use
ODD = (101, 333)


def image(channels, value=None, seed=1):
    rng = np.random.default_rng(seed)
    img = rng.uniform(0.05, 0.95, (H, W, channels)).astype(np.float32)
    if value is not None:
        img[ODD[0], ODD[1], channels - 1] = value
    return img


def alphas(value=None):
    """A one-channel image of slopes in [0.05, 0.15], ``value`` at the odd texel."""
    img = image(1) * 0.1 + 0.05
    if value is not None:
        img[ODD[0], ODD[1], 0] = value
    return img


def odd_texel_uv():
    return mi.Point2f((ODD[1] + 0.5) / W, (ODD[0] + 0.5) / H)


def bitmap(img, **extra):
    return {"type": "bitmap", "bitmap": mi.Bitmap(img), **extra}


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Images in the layouts Mitsuba stores: 8-bit sRGB and raw (bytes), 16-bit (half
    floats), EXR (float32), one channel."""
    d = tmp_path_factory.mktemp("layouts")
    img = image(3)
    Image.fromarray((img * 255).astype(np.uint8)).save(d / "rgb8.png")
    Image.fromarray((img[..., 0] * 255).astype(np.uint8)).save(d / "grey8.png")
    mi.Bitmap(img).convert(component_format=mi.Struct.Type.UInt16,
                           srgb_gamma=True).write(str(d / "rgb16.png"))
    mi.Bitmap(img).write(str(d / "rgb.exr"))
    mi.Bitmap(image(1)).write(str(d / "grey.exr"))
    return {"png8": {"type": "bitmap", "filename": str(d / "rgb8.png")},
            "png8_raw": {"type": "bitmap", "filename": str(d / "rgb8.png"), "raw": True},
            "grey8": {"type": "bitmap", "filename": str(d / "grey8.png")},
            "png16": {"type": "bitmap", "filename": str(d / "rgb16.png")},
            "exr": {"type": "bitmap", "filename": str(d / "rgb.exr")},
            "grey_exr": {"type": "bitmap", "filename": str(d / "grey.exr")}}


def ranges(entries, scalar):
    """name -> texture_range (or the reason it cannot be looked up so)."""
    out = {}
    for name, entry in entries.items():
        try:
            out[name] = P.texture_range(mi.load_dict(entry), scalar)
        except RuntimeError:
            out[name] = "cannot"
    return out


@pytest.mark.parametrize("scalar_variant, jit_variant",
                         [("scalar_rgb", "llvm_ad_rgb"), ("scalar_spectral", "llvm_ad_spectral")])
def test_scalar_variant_finds_the_ranges_of_llvm(files, monkeypatch, scalar_variant, jit_variant):
    """Every layout, looked up as a colour and as a float: the scalar variant's one-pass
    range is the LLVM variant's (which looks up all texels), and it looks up through
    Mitsuba a handful of texels, not every one."""
    lookups = []
    one = T._eval_range_scalar
    monkeypatch.setattr(T, "_eval_range_scalar", lambda *a: lookups.append(1) or one(*a))
    for scalar in (False, True):
        mi.set_variant(jit_variant)
        want = ranges(files, scalar)
        mi.set_variant(scalar_variant)
        lookups.clear()
        got = ranges(files, scalar)
        assert len(lookups) <= 5 * len(files)
        for name in files:
            if want[name] == "cannot":
                assert got[name] == "cannot", name
            else:
                assert got[name] == pytest.approx(want[name], rel=1e-5, abs=1e-7), name


@pytest.mark.parametrize("variant", ["scalar_rgb", "llvm_ad_rgb"])
@pytest.mark.parametrize("value, got", [(float("nan"), "NaN"), (-2.0, r"values in \[-2, ")])
def test_one_bad_texel_refused_at_load(variant, value, got):
    """One NaN or -2 at an odd texel of a 512 x 256 image is refused in every variant."""
    mi.set_variant(variant)
    with pytest.raises(RuntimeError,
                       match=rf"lambert: parameter 'reflectance' must be .*\(got {got}"):
        mi.load_dict({"type": "lambert", "reflectance": bitmap(image(3, value))})


def test_update_with_a_bad_texel_refused_and_taken_back():
    """scalar_rgb: a texel of -2 set by ``params.update()`` is refused, the texture gets its
    accepted values back, and the plugin evaluates as before."""
    mi.set_variant("scalar_rgb")
    bsdf = mi.load_dict({"type": "lambert", "reflectance": bitmap(image(3))})
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi, si.uv = mi.Vector3f(0, 0, 1), odd_texel_uv()
    before = bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(0, 0, 1))
    params = mi.traverse(bsdf)
    params["reflectance.data"] = mi.TensorXf(image(3, -2.0))
    with pytest.raises(P.ParameterError,
                       match=r"lambert: parameter 'reflectance' .*\(got values in \[-2, "):
        params.update()
    after = bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(0, 0, 1))
    assert list(after) == list(before) and min(after) > 0


def test_ward_alpha_zero_never_reaches_eval():
    """ward's alpha_u = 0 (a division by zero in a scalar variant's eval) is refused as a
    float, a spectrum, a texel of a bitmap, a square of a procedural texture and an
    update; the plugin keeps evaluating."""
    mi.set_variant("scalar_rgb")
    message = r"ward: parameter 'alpha_u' must be an RMS slope in \[0.0001, 1\] \(got "
    checkerboard = {"type": "checkerboard", "color0": 0.0, "color1": 0.2}
    for value in (0.0, {"type": "spectrum", "value": 0.0}, bitmap(alphas(0.0)), checkerboard):
        with pytest.raises(RuntimeError, match=message):
            mi.load_dict({"type": "ward", "alpha_u": value})
    bsdf = mi.load_dict({"type": "ward", "alpha_u": bitmap(alphas())})
    params = mi.traverse(bsdf)
    params["alpha_u.data"] = mi.TensorXf(alphas(0.0))
    with pytest.raises(P.ParameterError, match=message):
        params.update()
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi, si.uv = dr.normalize(mi.Vector3f(0.2, 0.1, 1)), odd_texel_uv()
    value = bsdf.eval(mi.BSDFContext(), si, dr.normalize(mi.Vector3f(-0.2, -0.1, 1)))
    assert all(math.isfinite(v) and v > 0 for v in value)


def test_refused_values_printed_with_their_digits():
    """1.0000001 is refused as 1.0000001, given as a float or held by a texture (as the
    float32 1.0000001192...), not as "1"."""
    mi.set_variant("scalar_rgb")
    texture = bitmap(np.full((2, 2, 1), 1.0000001, np.float32))
    for value in (1.0000001, {"type": "spectrum", "value": 1.0000001}, texture):
        with pytest.raises(RuntimeError, match=r"phong: parameter 'alpha' must be a roughness "
                           r"in \[0.0015, 1\] \(got 1.0000001\)"):
            mi.load_dict({"type": "phong", "alpha": value})
    assert P._num(P.float32(0.1)) == "0.1" and P._num(1e6) == "1e6" and P._num(2.0) == "2"


@pytest.mark.parametrize("eta", [float("inf"), 0.5])
def test_unbounded_range_says_infinity_is_refused(eta):
    mi.set_variant("scalar_rgb")
    with pytest.raises(RuntimeError, match=r"torrance_sparrow: parameter 'eta' must be a "
                       r"refractive index in \[1, inf\) \(got (inf|0.5)\)"):
        mi.load_dict({"type": "torrance_sparrow", "eta": eta})


def test_every_texture_parameter_has_a_range_in_the_manual():
    """Each row of a plugin page whose parameter is a checked texture states its range."""
    mi.set_variant("scalar_rgb")
    # the plugins as loaded by default, and with the parameters they read only on request
    configs = [{"type": p, **settings} for p in mitsuba_brdfs.plugin_models()
               for settings in ({},) + FACTS[p].on_request]
    for config in configs:
        rows = {p.name: p for p in manual.parameters(config["type"])}
        for name, rng in mi.load_dict(config)._ranges.items():
            if name in rows:
                assert rows[name].range, (config["type"], name)
