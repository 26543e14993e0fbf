"""Bitmap textures on every parameter of every plugin, as users' image files arrive.

Every colour parameter and every float parameter with a checked range (``_ranges``) of
every plugin takes a bitmap read from a file in each format users have: an 8-bit PNG
(sRGB), a 16-bit PNG (sRGB), a JPEG, an OpenEXR (linear) and an 8-bit PNG with
``raw = true`` (its bytes / 255, no sRGB decoding), in the RGB, mono and spectral LLVM
variants and, for the 8-bit PNG, in ``scalar_rgb``. Colours take RGB images, floats
one-channel ones. Each parameter alone loads; the plugin with all of its parameters
textured evaluates finite, >= 0, and like the plugin loaded with the constants the image
holds, decoded here from the file's codes (sRGB or linear). The range check reads what
the texture returns, so a mid-grey byte (128 -> 0.216) is accepted and an EXR of 2.0 on a
reflectance is refused where the BSDF would see 2.0 (RGB, mono). Spectral variants follow
Mitsuba's ``bitmap``: an RGB image becomes a fitted spectrum bounded by 1 (the EXR of
2.0 is accepted and gives 1, as Mitsuba's ``diffuse`` does), an RGB image cannot be read
as a float, nor a ``raw`` RGB image as a colour; those two are refused at load, naming
the parameter. ``lambert`` with a bitmap evaluates and samples exactly as ``diffuse``.
"""
import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from PIL import Image

import mitsuba_brdfs

PLUGINS = sorted(mitsuba_brdfs.plugin_models())
FORMATS = ("png8", "png16", "jpeg", "exr", "raw")
VARIANTS = ("llvm_ad_rgb", "llvm_ad_mono", "llvm_ad_spectral")

#: the images' contents: a colour for colour parameters, a grey for float parameters, and
#: a refractive index (EXR only: an 8-bit or 16-bit image holds values up to 1)
COLOUR_8, GREY_8 = (200, 120, 60), 128
COLOUR_F, GREY_F, ETA_F = (0.6, 0.35, 0.15), 0.3, 1.5
RES = 4

#: (wi, wo) pairs in the local frame, and uv points where the textures are looked up
PAIRS = [((0, 0, 1), (0, 0, 1)), ((0.6, 0, 0.8), (-0.6, 0, 0.8)),
         ((0.3, 0.5, 0.8124), (0.7, -0.2, 0.6855)), ((0.9, 0, 0.4359), (-0.2, 0.3, 0.9327))]
UVS = [(0.1, 0.2), (0.5, 0.5), (0.9, 0.7), (0.3, 0.95)]


# -- images ----------------------------------------------------------------------------------

def srgb_to_linear(c):
    """The sRGB transfer function, inverted (IEC 61966-2-1)."""
    c = np.asarray(c, np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def write_image(path, fmt, value):
    """A constant RES x RES image of ``value`` (a colour or a grey: bytes for 8-bit formats,
    linear floats otherwise) in format ``fmt``; returns its path."""
    channels = np.size(value)
    if fmt in ("png8", "jpeg", "raw"):
        arr = np.full((RES, RES, channels), value, np.uint8)
        img = Image.fromarray(arr if channels == 3 else arr[..., 0])
        img.save(path, **({"quality": 95} if fmt == "jpeg" else {}))
    else:
        bmp = mi.Bitmap(np.full((RES, RES, channels), value, np.float32))
        if fmt == "png16":
            bmp = bmp.convert(component_format=mi.Struct.Type.UInt16, srgb_gamma=True)
        bmp.write(str(path))
    return str(path)


def decoded(path, fmt):
    """The linear values a texture of the file returns (one per channel), from its codes."""
    codes = np.array(mi.Bitmap(path), dtype=np.float64)
    codes = codes.reshape(RES, RES, -1)[0, 0]
    if fmt == "exr":
        return codes
    scale = 65535.0 if fmt == "png16" else 255.0
    return codes / scale if fmt == "raw" else srgb_to_linear(codes / scale)


class Texture:
    """A bitmap file: its texture (a load_dict entry), what it returns, and its kind."""

    def __init__(self, path, fmt):
        self.path, self.fmt = path, fmt
        self.values = decoded(path, fmt)

    def tex(self, **extra):
        return {"type": "bitmap", "filename": self.path, **({"raw": True} if self.fmt == "raw" else {}),
                **extra}

    def constant(self):
        """The same values as a constant parameter."""
        if self.values.size == 3:
            return {"type": "rgb", "value": [float(v) for v in self.values]}
        return float(self.values[0])


@pytest.fixture(scope="module")
def images(tmp_path_factory):
    """(format, kind) -> Texture, kind in rgb (colour), grey (one channel), eta (EXR)."""
    d = tmp_path_factory.mktemp("images")
    ext = {"png8": "png", "png16": "png", "jpeg": "jpg", "exr": "exr", "raw": "png"}
    out = {}
    for fmt in FORMATS:
        eight = fmt in ("png8", "jpeg", "raw")
        for kind, value in (("rgb", COLOUR_8 if eight else COLOUR_F),
                            ("grey", GREY_8 if eight else GREY_F)):
            path = write_image(d / f"{kind}_{fmt}.{ext[fmt]}", fmt, value)
            out[fmt, kind] = Texture(path, fmt)
    out["exr", "eta"] = Texture(write_image(d / "eta.exr", "exr", ETA_F), "exr")
    return out


def test_images_hold_what_is_expected(images):
    """The decoding the other tests expect: 8-bit sRGB bytes become linear (128 -> 0.216),
    raw bytes are divided by 255, 16-bit and EXR keep the written values."""
    np.testing.assert_allclose(images["png8", "grey"].values, 0.2158605, rtol=1e-6)
    np.testing.assert_allclose(images["raw", "grey"].values, 128 / 255, rtol=1e-6)
    np.testing.assert_allclose(images["jpeg", "rgb"].values,
                               srgb_to_linear(np.array(COLOUR_8) / 255), atol=0.01)
    np.testing.assert_allclose(images["png16", "rgb"].values, COLOUR_F, rtol=1e-4)
    np.testing.assert_allclose(images["exr", "rgb"].values, COLOUR_F, rtol=1e-6)


# -- which image each parameter takes -------------------------------------------------------

def parameters(plugin):
    """parameter -> (is a colour, Range) of the plugin's checked parameters."""
    return {name: (not rng.scalar, rng) for name, rng in mi.load_dict({"type": plugin})._ranges.items()}


def image_for(images, fmt, colour, rng, spectral):
    """The image a parameter takes in format ``fmt``, or None where no image of the format
    holds a value of its range (a refractive index in an 8-bit or 16-bit image).

    Colours take RGB images, except ``raw`` ones in spectral variants, which Mitsuba's
    bitmap cannot turn into spectra (``test_spectral_raw_rgb_colour_refused``): those take
    the grey one.
    """
    if rng.lo > 0.5:
        return images.get((fmt, "eta"))
    if colour and not (spectral and fmt == "raw"):
        return images[fmt, "rgb"]
    return images[fmt, "grey"]


def textured_and_constant(images, plugin, fmt):
    """The plugin with every parameter an image of format ``fmt``, and with the constants
    those images hold (load_dict entries)."""
    textured, constant = {"type": plugin}, {"type": plugin}
    for name, (colour, rng) in parameters(plugin).items():
        img = image_for(images, fmt, colour, rng, mi.is_spectral)
        if img is not None:
            textured[name], constant[name] = img.tex(), img.constant()
    return textured, constant


def interactions():
    """PAIRS x UVS as one SurfaceInteraction3f and wo (JIT variants)."""
    wi = np.array([p[0] for p in PAIRS for _ in UVS], np.float64)
    wo = np.array([p[1] for p in PAIRS for _ in UVS], np.float64)
    uv = np.array([uv for _ in PAIRS for uv in UVS], np.float64)
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi = mi.Vector3f(*wi.T)
    si.uv = mi.Point2f(*uv.T)
    if mi.is_spectral:
        si.wavelengths = mi.Spectrum(*(np.full(len(wi), w) for w in (450.0, 520.0, 600.0, 680.0)))
    return si, mi.Vector3f(*wo.T)


def evaluate(bsdf, si, wo):
    return np.array(bsdf.eval(mi.BSDFContext(), si, wo), dtype=np.float64)


# -- 1. every parameter, every format, every variant ------------------------------------------

@pytest.mark.parametrize("variant", VARIANTS + ("llvm_ad_spectral_polarized",))
def test_bitmap_on_each_parameter_loads(images, variant):
    """Each parameter alone, given an image of each format, loads (the range check accepts
    the values the texture returns; in a polarized variant too)."""
    mi.set_variant(variant)
    failures = []
    for plugin in PLUGINS:
        for name, (colour, rng) in parameters(plugin).items():
            for fmt in FORMATS:
                img = image_for(images, fmt, colour, rng, mi.is_spectral)
                if img is None:
                    continue
                try:
                    mi.load_dict({"type": plugin, name: img.tex()})
                except Exception as e:  # noqa: BLE001  (collected, reported below)
                    failures.append(f"{plugin}.{name} {fmt}: {str(e).splitlines()[-1]}")
    assert not failures, f"{variant}:\n" + "\n".join(failures)


@pytest.mark.parametrize("variant", VARIANTS)
def test_bitmaps_evaluate_like_their_values(images, variant):
    """Every plugin with all of its parameters textured, in each format, evaluates finite
    and >= 0, and like the plugin loaded with the values its images hold (to the half
    precision Mitsuba stores 8- and 16-bit images in); textured, it says it is spatially
    varying, with constants not."""
    mi.set_variant(variant)
    si, wo = interactions()
    failures = []
    for plugin in PLUGINS:
        for fmt in FORMATS:
            textured, constant = (mi.load_dict(d) for d in
                                  textured_and_constant(images, plugin, fmt))
            got, want = evaluate(textured, si, wo), evaluate(constant, si, wo)
            tag = f"{plugin} {fmt}"
            if not (textured.flags() & mi.BSDFFlags.SpatiallyVarying
                    and not constant.flags() & mi.BSDFFlags.SpatiallyVarying):
                failures.append(f"{tag}: textured or not, the flags say the same")
            if not (np.isfinite(got).all() and (got >= 0).all() and got.max() > 0):
                failures.append(f"{tag}: eval gives {got.min()}..{got.max()}")
            elif not np.allclose(got, want, rtol=3e-3, atol=1e-6):
                failures.append(f"{tag}: eval {got.ravel()[:4]} vs constants {want.ravel()[:4]}")
    assert not failures, f"{variant}:\n" + "\n".join(failures)


def test_scalar_variant_with_8bit_png(images):
    """scalar_rgb: every plugin with all of its parameters 8-bit PNG bitmaps loads and
    evaluates like the plugin with the decoded constants (the range check looks the texels
    up one by one there)."""
    mi.set_variant("scalar_rgb")
    failures = []
    for plugin in PLUGINS:
        textured, constant = (mi.load_dict(d) for d in textured_and_constant(images, plugin, "png8"))
        for (wi, wo), uv in zip(PAIRS, UVS):
            si = dr.zeros(mi.SurfaceInteraction3f)
            si.wi, si.uv = dr.normalize(mi.Vector3f(*wi)), mi.Point2f(*uv)
            w = dr.normalize(mi.Vector3f(*wo))
            got, want = evaluate(textured, si, w), evaluate(constant, si, w)
            if not (np.isfinite(got).all() and (got >= 0).all()):
                failures.append(f"{plugin} {wi}: {got}")
            elif not np.allclose(got, want, rtol=3e-3, atol=1e-6):
                failures.append(f"{plugin} {wi}: {got} vs constants {want}")
    assert not failures, "\n".join(failures)


def inside(rng, t):
    """A value a fraction t into the range (into [lo, lo + 1] for an unbounded one)."""
    return rng.lo + t * (min(rng.hi, rng.lo + 1.0) - rng.lo)


@pytest.mark.parametrize("variant", ["llvm_ad_rgb", "llvm_ad_spectral"])
def test_procedural_textures_on_every_parameter(variant):
    """Every parameter of every plugin a ``checkerboard`` of two values of its range: the
    plugin loads, evaluates finite and >= 0, and differs between the two kinds of squares
    (uv (0.25, 0.25) and (0.75, 0.25))."""
    mi.set_variant(variant)
    si, wo = interactions()
    si.uv = mi.Point2f(*np.array([(0.25, 0.25), (0.75, 0.25)] * (dr.width(si) // 2)).T)
    failures = []
    for plugin in PLUGINS:
        d = {"type": plugin}
        for name, (colour, rng) in parameters(plugin).items():
            d[name] = {"type": "checkerboard", "color0": inside(rng, 0.3), "color1": inside(rng, 0.7)}
        got = evaluate(mi.load_dict(d), si, wo)
        if not (np.isfinite(got).all() and (got >= 0).all()):
            failures.append(f"{plugin}: {got.min()}..{got.max()}")
        elif np.allclose(got[:, 0::2], got[:, 1::2]):
            failures.append(f"{plugin}: the checkerboard does not show")
    assert not failures, f"{variant}:\n" + "\n".join(failures)


# -- 2. values outside the range, and images a variant cannot read ------------------------------

def colour_parameters(plugin):
    return [name for name, (colour, _) in parameters(plugin).items() if colour]


def float_parameters(plugin):
    return [name for name, (colour, rng) in parameters(plugin).items()
            if not colour and rng.lo <= 0.5]


@pytest.fixture(scope="module")
def exr_two(tmp_path_factory):
    d = tmp_path_factory.mktemp("two")
    return (write_image(d / "two_rgb.exr", "exr", (2.0, 2.0, 2.0)),
            write_image(d / "two_grey.exr", "exr", 2.0))


@pytest.mark.parametrize("variant", ["llvm_ad_rgb", "llvm_ad_mono"])
def test_exr_above_one_refused_on_reflectances(exr_two, variant):
    """An EXR of 2.0 on any reflectance is refused, the message naming plugin and parameter."""
    mi.set_variant(variant)
    for plugin in PLUGINS:
        for name in colour_parameters(plugin):
            with pytest.raises(RuntimeError) as err:
                mi.load_dict({"type": plugin, name: {"type": "bitmap", "filename": exr_two[0]}})
            assert (f"{plugin}: parameter '{name}' must be a reflectance in [0, 1]"
                    in str(err.value)), str(err.value)
            assert "(got 2)" in str(err.value)


def test_exr_above_one_in_spectral_is_a_bounded_spectrum(exr_two):
    """Spectral variants fit a spectrum bounded by 1 to an RGB image (Mitsuba's bitmap): the
    EXR of 2.0 is accepted on every reflectance and evaluates to 1 as in ``diffuse``; a
    one-channel EXR of 2.0 is not fitted and stays refused."""
    mi.set_variant("llvm_ad_spectral")
    rgb, grey = exr_two
    for plugin in PLUGINS:
        for name in colour_parameters(plugin):
            mi.load_dict({"type": plugin, name: {"type": "bitmap", "filename": rgb}})
            with pytest.raises(RuntimeError, match=f"{plugin}: parameter '{name}' must be a "
                                                   r"reflectance in \[0, 1\].*\(got 2\)"):
                mi.load_dict({"type": plugin, name: {"type": "bitmap", "filename": grey}})
    si, wo = interactions()
    lam = evaluate(mi.load_dict({"type": "lambert", "reflectance": {"type": "bitmap", "filename": rgb}}), si, wo)
    dif = evaluate(mi.load_dict({"type": "diffuse", "reflectance": {"type": "bitmap", "filename": rgb}}), si, wo)
    np.testing.assert_allclose(lam, dif, rtol=1e-6, atol=1e-9)
    cos = np.array(wo.z, dtype=np.float64)
    np.testing.assert_allclose(lam * np.pi / cos[None, :], 1.0, rtol=1e-5)


def test_spectral_raw_rgb_colour_refused(images):
    """A spectral variant cannot turn a ``raw`` RGB image into spectra (Mitsuba's bitmap
    raises when it is looked up, ``diffuse`` included): refused at load, naming the plugin,
    the parameter and the reason."""
    mi.set_variant("llvm_ad_spectral")
    for plugin in PLUGINS:
        for name in colour_parameters(plugin):
            with pytest.raises(RuntimeError) as err:
                mi.load_dict({"type": plugin, name: images["raw", "rgb"].tex()})
            msg = str(err.value)
            assert f"{plugin}: parameter '{name}' must be a reflectance" in msg, msg
            assert "cannot read as a colour" in msg and "raw=true" in msg, msg


@pytest.mark.parametrize("variant", VARIANTS)
def test_rgb_image_on_float_parameters(images, variant):
    """An RGB image on a float parameter is read as its luminance (rgb, mono, and raw in
    spectral); in a spectral variant a non-raw one is a spectrum, which Mitsuba cannot read
    as a float: refused at load, naming the parameter."""
    mi.set_variant(variant)
    png, raw = images["png8", "rgb"], images["raw", "rgb"]
    for plugin in PLUGINS:
        for name in float_parameters(plugin):
            mi.load_dict({"type": plugin, name: raw.tex()})
            if not mi.is_spectral:
                mi.load_dict({"type": plugin, name: png.tex()})
                continue
            with pytest.raises(RuntimeError) as err:
                mi.load_dict({"type": plugin, name: png.tex()})
            msg = str(err.value)
            assert f"{plugin}: parameter '{name}' must be" in msg, msg
            assert "cannot read as a float" in msg, msg


# -- 3. lambert with a bitmap is diffuse with it ----------------------------------------------

@pytest.fixture(scope="module")
def varied_png(tmp_path_factory):
    """An 8 x 8 8-bit PNG of random colours."""
    rng = np.random.default_rng(5)
    path = tmp_path_factory.mktemp("varied") / "varied.png"
    Image.fromarray(rng.integers(0, 256, (8, 8, 3), dtype=np.uint8)).save(path)
    return str(path)


@pytest.mark.parametrize("variant", VARIANTS)
def test_lambert_with_bitmap_equals_diffuse(varied_png, variant):
    """eval and sample of ``lambert`` and ``diffuse`` with the same 8-bit PNG agree exactly,
    at many points of the texture (bilinear lookups between texels)."""
    mi.set_variant(variant)
    tex = {"type": "bitmap", "filename": varied_png}
    lam = mi.load_dict({"type": "lambert", "reflectance": tex})
    dif = mi.load_dict({"type": "diffuse", "reflectance": tex})
    n = 4096
    rng = np.random.default_rng(1)
    wi = rng.normal(size=(n, 3))
    wi[:, 2] = np.abs(wi[:, 2])
    wo = rng.normal(size=(n, 3))
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = dr.normalize(mi.Vector3f(*wi.T))
    si.uv = mi.Point2f(*rng.uniform(0, 1, (2, n)))
    if mi.is_spectral:
        si.wavelengths = mi.Spectrum(*rng.uniform(360, 830, (4, n)))
    wo = dr.normalize(mi.Vector3f(*wo.T))
    ctx = mi.BSDFContext()
    f_l, f_d = evaluate(lam, si, wo), evaluate(dif, si, wo)
    assert f_d.max() > 0.05
    np.testing.assert_allclose(f_l, f_d, rtol=1e-6, atol=1e-9)
    s1, s2 = mi.Float(rng.uniform(0, 1, n)), mi.Point2f(*rng.uniform(0, 1, (2, n)))
    (bs_l, w_l), (bs_d, w_d) = lam.sample(ctx, si, s1, s2), dif.sample(ctx, si, s1, s2)
    np.testing.assert_allclose(np.array(w_l), np.array(w_d), rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(np.array(bs_l.wo), np.array(bs_d.wo), rtol=1e-6, atol=1e-7)
