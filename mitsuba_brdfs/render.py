"""Rendering scenes in passes and writing images whole; the ``render`` command.

Mitsuba renders all samples of a call at once, so the memory of a call can grow with
width x height x spp (how much depends on the integrator; ``docs/performance.md``
measures it). ``render_image`` splits the samples into passes of bounded size, made one
at a time (a huge spp costs nothing before the first pixel), and averages the film's
images (each pass weighted by the samples the sampler really took: ``stratified`` and
other samplers round a count up). ``write_exr`` / ``write_png`` / ``write_jpeg`` write
to a temporary file beside the target and rename it, so an interrupted command never
leaves a half-written image.

The ``render`` command (Mitsuba's C++ ``mitsuba`` executable cannot load Python plugins;
its options are kept where they exist: ``-m``, ``-t``, ``-s``, ``-D``, ``-a``, ``-o``,
``-v``)::

    python -m mitsuba_brdfs render scenes/as_sphere.xml -o as_sphere --spp 64

What it writes, by the extension of ``-o`` (default: the scene's name, in the current
directory):

- no extension: ``NAME.exr`` (the film: every channel, its names and pixel format) and
  ``NAME.png`` (the colour, tone-mapped to 8-bit sRGB);
- ``.exr``: that EXR alone;
- ``.png``, ``.jpg``: that image, and the EXR beside it (``NAME.exr``) unless
  ``--no-exr``, so the HDR image is never dropped without being asked.

Everything that can be checked is checked before rendering: the outputs' formats and
folders, that no output is the scene or a file it loads, the variant, the scene, its
sensor and sample count.
"""
import collections
import contextlib
import functools
import math
import os
import re
import sys
import tempfile
import time

import numpy as np

from .arguments import (UINT32_MAX, UsageError, define, finite_float, nonnegative_int,
                        positive_int, uint32)

__all__ = ["DEFAULT_PASS_SAMPLES", "WRITES_ATOMICALLY", "set_variant", "check_variant",
           "load_scene", "scene_spp", "passes", "pass_sizes", "pass_seed", "progress_bar",
           "advance", "Rendered", "render_image", "render_passes", "write_exr", "read_exr",
           "write_png", "write_jpeg", "tonemap", "written", "plan_outputs", "check_not_input",
           "check_outputs", "check_folder", "scene_inputs", "add_arguments", "run"]

#: samples (pixels x spp) traced at once; bounds the memory of one pass (~1-2 GiB)
DEFAULT_PASS_SAMPLES = 1 << 22

#: every file of this command goes through ``_atomic``: an interruption can say what was written
WRITES_ATOMICALLY = True

#: Mitsuba's variant names: backend, AD, colour, polarization, precision
_VARIANT = re.compile(r"(scalar|llvm|cuda|metal)(_ad)?_(rgb|mono|spectral)(_polarized)?(_double)?$")


# -- variant and scene --------------------------------------------------------------------

def check_variant(variant):
    """Raise ``UsageError`` (or ``LLVMVersionError``) unless ``variant`` can run here.

    Checked before ``mi.set_variant``: it must be built into this Mitsuba, and its JIT
    backend must be present (a CUDA GPU, or a libLLVM of a release Dr.Jit can use).
    """
    import mitsuba as mi
    built = mi.variants()
    if variant not in built:
        what = (f"variant {variant!r} is not built into this Mitsuba" if _VARIANT.match(variant)
                else f"unknown variant {variant!r}")
        raise UsageError(f"{what} (it has {', '.join(built)})")
    if variant.startswith("llvm_"):
        from .core.llvm import check_llvm
        check_llvm(variant)
    elif variant.startswith("cuda_"):
        import drjit as dr
        if not dr.has_backend(dr.JitBackend.CUDA):
            raise UsageError(f"variant {variant!r} needs an NVIDIA GPU and its CUDA driver; "
                             f"Dr.Jit found none (the llvm_* variants run on the CPU)")


def set_variant(variant):
    """Activate ``variant`` (and register the plugins in it), after ``check_variant``."""
    import mitsuba as mi
    if mi.variant() != variant:
        check_variant(variant)
        mi.set_variant(variant)
    import mitsuba_brdfs
    mitsuba_brdfs.register()


def load_scene(path, defines=None):
    """``mi.load_file`` with ``<default>`` overrides (strings, as ``-D key=value`` gives)."""
    import mitsuba as mi
    return mi.load_file(str(path), **{k: str(v) for k, v in (defines or {}).items()})


def scene_spp(scene, sensor=0):
    return scene.sensors()[sensor].sampler().sample_count()


# -- passes -------------------------------------------------------------------------------

def _sample_counter(sampler):
    """``count(n)``: the samples per pixel ``sampler`` really takes when asked for ``n``
    (``stratified``, ``ldsampler``, ... round up to their grids). Probing is silent and
    leaves the sampler's own count as it was."""
    import mitsuba as mi
    cache = {}

    def count(n):
        if n not in cache:
            old, level = sampler.sample_count(), mi.log_level()
            mi.set_log_level(mi.LogLevel.Error)  # the rounding warning of each probe
            try:
                sampler.set_sample_count(n)
                cache[n] = sampler.sample_count()
                sampler.set_sample_count(old)
            finally:
                mi.set_log_level(level)
        return cache[n]
    return count


def _largest_valid(count, want):
    """The largest count the sampler takes that is <= ``want`` (``count`` rounds up and
    grows with its argument), or its smallest one if all are larger."""
    if count(want) <= want:
        return count(want)
    lo, hi = 1, want  # count(hi) > want
    if count(lo) > want:
        return count(lo)
    # count(lo) <= want < count(hi): bisect
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if count(mid) <= want else (lo, mid)
    return count(lo)


def passes(spp, pixels, pass_samples=DEFAULT_PASS_SAMPLES, count=None):
    """Yield the spp of each pass, lazily: at most ``pass_samples`` samples a pass (and
    at least 1 spp), at most ``UINT32_MAX`` spp (Mitsuba's limit).

    With ``count=None`` every count is valid and the passes are balanced (they differ by
    at most one spp) and add up to ``spp``. Otherwise ``count(n)`` is the count the
    sampler really takes for ``n`` (``_sample_counter``): each pass is the largest valid
    count that fits, and the passes add up to at least ``spp`` (more only when no valid
    count fits the remainder).
    """
    per = max(1, min(spp, pass_samples // max(pixels, 1), UINT32_MAX))
    if count is None:
        n = math.ceil(spp / per)
        base, extra = divmod(spp, n)
        for i in range(n):
            yield base + (i < extra)
        return
    done = 0
    while done < spp:
        n = _largest_valid(count, min(spp - done, per))
        yield n
        done += n


def pass_sizes(spp, pixels, pass_samples=DEFAULT_PASS_SAMPLES):
    """The list of ``passes`` (for small counts; a huge spp makes a huge list)."""
    return list(passes(spp, pixels, pass_samples))


def pass_seed(seed, index):
    """Seed of pass ``index``: ``seed`` itself for the first pass (a one-pass render is
    ``mi.render(scene, seed=seed)``), then a 32-bit hash of (seed, index), so passes and
    renders with other seeds do not share their samples."""
    if index == 0:
        return seed
    return int(np.random.SeedSequence([seed, index]).generate_state(1)[0])


# -- progress -----------------------------------------------------------------------------

def _hms(seconds):
    """Seconds as h:mm:ss."""
    s = int(round(seconds))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


@functools.lru_cache(maxsize=None)
def _bar_class():
    from tqdm import tqdm

    class Bar(tqdm):
        """tqdm with the elapsed time and the time left (ETA) as h:mm:ss."""

        @property
        def format_dict(self):
            d = super().format_dict
            elapsed, done = d["elapsed"], d["n"] - d.get("initial", 0)
            rate = d["rate"] or (done / elapsed if elapsed and done else None)
            left = (d["total"] - d["n"]) / rate if rate and d["total"] else None
            d["elapsed_hms"] = _hms(elapsed)
            d["eta"] = _hms(left) if left is not None else "?"
            return d
    return Bar


def progress_bar(total, label, unit="it", enabled=True):
    """A tqdm progress bar on stderr, with the time spent and the time left as h:mm:ss.
    Where stderr is not a terminal (a CI log) it is redrawn at most every 5 seconds, so
    logs stay short."""
    bar_format = ("{desc}: {percentage:3.0f}%|{bar}| {n_fmt}/{total_fmt} {unit} "
                  "[{elapsed_hms} spent, ETA {eta}{postfix}]")
    return _bar_class()(total=total, desc=label, unit=unit, file=sys.stderr,
                        disable=not enabled, bar_format=bar_format,
                        unit_scale=bool(total and total >= 100_000),
                        mininterval=0.1 if sys.stderr.isatty() else 5.0, dynamic_ncols=True)


def advance(bar, n=1, note=""):
    """Count ``n`` more steps done on ``bar`` (a ``progress_bar``, or None) and show ``note``
    beside it."""
    if bar is not None:
        bar.set_postfix_str(note, refresh=False)
        bar.update(n)


# -- rendering ----------------------------------------------------------------------------

#: a rendered film: image (float32, H x W x C) and its channel names, spp really taken,
#: passes, seconds of JIT compilation and of rendering (the compilation included)
Rendered = collections.namedtuple("Rendered", "image channels spp passes compile_seconds seconds")


def _film_image(film):
    """The film's developed image as Mitsuba's ``mitsuba`` writes it (``film.bitmap()``):
    float32 (H, W, C) and its channel names."""
    bmp = film.bitmap()
    names = [bmp.struct_()[i].name for i in range(bmp.channel_count())]
    img = np.array(bmp, dtype=np.float32, copy=True)
    return img.reshape(img.shape[0], img.shape[1], -1), names


def render_image(scene, spp=None, pass_samples=DEFAULT_PASS_SAMPLES, seed=0, sensor=0,
                 label="render", progress=True, integrator=None, measure_compile=False):
    """Render ``scene`` with ``spp`` samples per pixel (default: its sampler's) in passes.

    Returns a ``Rendered``. The image is the film's (``film.bitmap()``): every channel
    with its name (AOVs included), in the film's pixel format (RGB, luminance or XYZ, with
    or without alpha). Pass ``i`` uses seed ``pass_seed(seed, i)``. ``measure_compile``
    records Dr.Jit's kernel history to tell JIT compilation apart.
    """
    import drjit as dr
    import mitsuba as mi

    sensor_obj = scene.sensors()[sensor]
    count = _sample_counter(sensor_obj.sampler())
    spp = spp or sensor_obj.sampler().sample_count()
    total = count(spp) if spp <= UINT32_MAX else spp
    film = sensor_obj.film()
    w, h = film.crop_size()
    acc, done, compile_ms, n_passes = None, 0, 0.0, 0
    flag = (dr.scoped_set_flag(dr.JitFlag.KernelHistory, True) if measure_compile
            else contextlib.nullcontext())
    t0 = time.perf_counter()
    with progress_bar(total, label, "spp", enabled=progress) as bar, flag:
        if measure_compile:
            dr.kernel_history_clear()
        for i, n in enumerate(passes(total, w * h, pass_samples, count)):
            mi.render(scene, spp=n, seed=pass_seed(seed, i), sensor=sensor, integrator=integrator)
            img, names = _film_image(film)
            acc = img.astype(np.float64) * n if acc is None else acc + img * n
            done += n
            n_passes = i + 1
            dr.flush_malloc_cache()
            if measure_compile:
                compile_ms += sum(k.get("codegen_time", 0) + k.get("backend_time", 0)
                                  for k in dr.kernel_history())
            if bar.total is not None and done > bar.total:
                bar.total = done  # the sampler's rounding of the last pass
            advance(bar, n, f"pass {n_passes}")
    seconds = time.perf_counter() - t0
    return Rendered((acc / done).astype(np.float32), names, done, n_passes, compile_ms / 1e3,
                    seconds)


def render_passes(scene, spp=None, pass_samples=DEFAULT_PASS_SAMPLES, seed=0, sensor=0,
                  label="render", progress=True, integrator=None):
    """``render_image``'s image and seconds: (float32 (H, W, C), seconds)."""
    r = render_image(scene, spp, pass_samples, seed, sensor, label, progress, integrator)
    return r.image, r.seconds


# -- files --------------------------------------------------------------------------------

_WRITTEN = []


def written(clear=False):
    """The files written whole (through ``_atomic``) since the last ``written(clear=True)``."""
    files = list(_WRITTEN)
    if clear:
        _WRITTEN.clear()
    return files


@contextlib.contextmanager
def _atomic(path):
    """Yield a temporary path in the target's directory; rename it over ``path`` on success.

    The temporary file is removed whatever stops the write, a signal included (the command
    line turns SIGINT and SIGTERM into exceptions, so this ``finally`` runs)."""
    path = os.fspath(path)
    directory = os.path.dirname(os.path.abspath(path))
    os.makedirs(directory, exist_ok=True)
    suffix = os.path.splitext(path)[1]
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(prefix=".partial-", suffix=suffix, dir=directory)
        os.close(fd)
        yield tmp
        # mkstemp creates the file readable by its owner only: give it the mode of any
        # new file (0o666 less the umask)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
        _WRITTEN.append(path)
    finally:
        if tmp is not None and os.path.exists(tmp):
            os.remove(tmp)


def _default_channels(c):
    return {1: ["Y"], 2: ["Y", "A"], 3: ["R", "G", "B"], 4: ["R", "G", "B", "A"]}.get(
        c, [f"C{i}" for i in range(c)])


def _write_bitmap(bmp, path, file_format):
    bmp.write(path, file_format)


def write_exr(path, image, channels=None):
    """Write a float32 (H, W, C) image as a ZIP-compressed OpenEXR file, atomically.

    ``channels`` names the channels (default: Y, YA, RGB or RGBA by their count); X, Y, Z
    images carry the XYZ chromaticities, as Mitsuba's films write them. (The OpenEXR
    module, not ``mi.Bitmap.write``: Mitsuba's EXR writer hangs with a thread pool of one.)
    """
    import OpenEXR
    img = np.ascontiguousarray(np.asarray(image, dtype=np.float32))
    if img.ndim == 2:
        img = img[..., None]
    names = list(channels or _default_channels(img.shape[2]))
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    if names[:3] == ["X", "Y", "Z"]:
        header["chromaticities"] = (1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1 / 3, 1 / 3)
    pixels = {n: np.ascontiguousarray(img[..., i]) for i, n in enumerate(names)}
    with _atomic(path) as tmp:
        _write_openexr(header, pixels, tmp)


def _write_openexr(header, pixels, path):
    import OpenEXR
    with OpenEXR.File(header, pixels) as f:
        f.write(path)


#: channel orders of the usual images (OpenEXR stores channels sorted by name)
_ORDERS = (["R", "G", "B", "A"], ["X", "Y", "Z", "A"], ["Y", "A"])


def read_exr(path, names=False):
    """Read an OpenEXR file as float32 (H, W, C) (and its channel names if ``names``):
    colour channels first (R, G, B, A or X, Y, Z, A or Y, A), the others by name."""
    import OpenEXR
    with OpenEXR.File(os.fspath(path), separate_channels=True) as f:
        chans = {k: v.pixels for k, v in f.channels().items()}
    order = []
    for colour in _ORDERS:
        if colour[0] in chans and (colour[0] != "Y" or "X" not in chans):
            order = [c for c in colour if c in chans]
            break
    order += sorted(set(chans) - set(order))
    img = np.stack([np.asarray(chans[n], dtype=np.float32) for n in order], axis=-1)
    return (img, order) if names else img


def _color(image, channels):
    """The colour of a film image as linear sRGB (H, W, 3), or its luminance (H, W, 1)."""
    import mitsuba as mi
    image = np.asarray(image, dtype=np.float32)
    names = list(channels or _default_channels(image.shape[2]))
    if names[:3] == ["R", "G", "B"]:
        return image[..., :3]
    if names[:3] == ["X", "Y", "Z"]:
        xyz = mi.Bitmap(np.ascontiguousarray(image[..., :3]), pixel_format=mi.Bitmap.PixelFormat.XYZ)
        return np.array(xyz.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False))
    if names[:1] == ["Y"]:
        return image[..., :1]
    raise ValueError(f"no colour channels (RGB, XYZ or Y) among {', '.join(names)}")


def tonemap(image, exposure=0.0):
    """Linear RGB (or luminance) -> 8-bit sRGB (clamped): (H, W, 3) (or (H, W, 1)) uint8."""
    x = np.asarray(image, dtype=np.float64)[..., :3] * 2.0 ** exposure
    x = np.clip(np.nan_to_num(x, nan=0.0, posinf=1.0), 0.0, 1.0)
    srgb = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.round(srgb * 255).astype(np.uint8)


def _write_ldr(path, image, exposure, already_tonemapped, file_format, channels=None):
    import mitsuba as mi
    img = np.asarray(image)
    if img.ndim == 2:
        img = img[..., None]
    if not already_tonemapped:
        img = tonemap(_color(img, channels), exposure)
    img = np.array(img, dtype=np.uint8, order="C")
    fmt = mi.Bitmap.PixelFormat.Y if img.shape[2] == 1 else mi.Bitmap.PixelFormat.RGB
    bmp = mi.Bitmap(img, pixel_format=fmt)
    with _atomic(path) as tmp:
        _write_bitmap(bmp, tmp, file_format)


def write_png(path, image, exposure=0.0, already_tonemapped=False, channels=None):
    """Write an 8-bit sRGB PNG, atomically: the colour of ``image`` (RGB, XYZ or luminance
    by ``channels``; alpha and AOVs are left out) tone-mapped from linear with
    ``exposure`` stops, unless ``already_tonemapped`` (uint8 RGB or grey)."""
    import mitsuba as mi
    _write_ldr(path, image, exposure, already_tonemapped, mi.Bitmap.FileFormat.PNG, channels)


def write_jpeg(path, image, exposure=0.0, already_tonemapped=False, channels=None):
    """``write_png`` as a JPEG (quality 100)."""
    import mitsuba as mi
    _write_ldr(path, image, exposure, already_tonemapped, mi.Bitmap.FileFormat.JPEG, channels)


# -- outputs ------------------------------------------------------------------------------

_FORMATS = {".exr": "exr", ".png": "png", ".jpg": "jpeg", ".jpeg": "jpeg"}


def plan_outputs(scene_path, output=None, exr=True):
    """The files ``render`` writes, as [(path, format)] with format exr, png or jpeg (the
    rule of the module's docstring)."""
    if output is None:
        output = os.path.splitext(os.path.basename(os.fspath(scene_path)))[0]
    output = os.fspath(output)
    if output.endswith(("/", os.sep)) or os.path.isdir(output):
        raise UsageError(f"-o {output}: is a folder; name the image, e.g. "
                         f"{os.path.join(output, 'image.exr')}")
    stem, ext = os.path.splitext(output)
    kind = _FORMATS.get(ext.lower())
    if ext and kind is None:
        raise UsageError(f"-o {output}: cannot write {ext!r} images; use .exr, .png, .jpg "
                         f"or no extension (EXR + PNG)")
    if not ext:
        plan = [(output + ".exr", "exr"), (output + ".png", "png")]
    elif kind == "exr":
        plan = [(output, "exr")]
    else:
        plan = [(stem + ".exr", "exr"), (output, kind)]
    if not exr:
        if kind == "exr":
            raise UsageError(f"--no-exr with -o {output}: nothing would be written")
        plan = [p for p in plan if p[1] != "exr"]
    return plan


def scene_inputs(scene_path, search_paths=()):
    """The files a scene reads: itself, and the files its ``filename`` strings and
    ``<include>`` elements name (found beside the scene, in ``search_paths`` or the
    current directory), as real paths. Values with ``$`` parameters are left out."""
    import xml.etree.ElementTree as ET
    scene_path = os.fspath(scene_path)
    found = {os.path.realpath(scene_path)}
    try:
        root = ET.parse(scene_path).getroot()
    except (ET.ParseError, OSError):
        return found  # Mitsuba reports it when loading
    folders = [os.path.dirname(os.path.abspath(scene_path)), *search_paths, os.getcwd()]
    for el in root.iter():
        value = el.get("filename") if el.tag == "include" else (
            el.get("value") if el.get("name") == "filename" else None)
        if not value or "$" in value:
            continue
        for folder in folders:
            candidate = os.path.join(folder, value)
            if os.path.isfile(candidate):
                found.add(os.path.realpath(candidate))
                break
    return found


def check_not_input(path, scene_path, inputs=()):
    """Refuse (``UsageError``) ``path`` as an output if it is the scene or in ``inputs``."""
    real = os.path.realpath(os.fspath(path))
    if real == os.path.realpath(os.fspath(scene_path)):
        raise UsageError(f"-o {path}: that is the scene itself; refusing to overwrite it")
    if real in inputs:
        raise UsageError(f"-o {path}: that is a file the scene loads; refusing to overwrite it")


def check_outputs(outputs, scene_path, inputs=()):
    """Refuse (``UsageError``) an output that is an input, a folder, or in a folder that
    cannot be created or written."""
    for path, _ in outputs:
        check_not_input(path, scene_path, inputs)
        if os.path.isdir(path):
            raise UsageError(f"-o {path}: is a folder; name the image")
        check_folder(os.path.dirname(os.path.abspath(path)), f"cannot write {path}")


def check_folder(folder, what=None):
    """Refuse (``UsageError``) a folder that cannot be created or written into: its
    nearest existing ancestor must be a folder where a file can be created (the only
    reliable test: root passes ``os.access``). Creates nothing that stays."""
    what = what or f"cannot write into {folder}"
    existing = os.path.abspath(folder)
    while not os.path.exists(existing):
        existing = os.path.dirname(existing)
    if not os.path.isdir(existing):
        raise UsageError(f"{what}: {existing} is not a folder")
    try:
        fd, probe = tempfile.mkstemp(prefix=".partial-", dir=existing)
        os.close(fd)
        os.remove(probe)
    except OSError as e:
        raise UsageError(f"{what}: {existing}: {e.strerror}") from None


def _write_outputs(rendered, outputs, exposure):
    for path, kind in outputs:
        if kind == "exr":
            write_exr(path, rendered.image, rendered.channels)
        elif kind == "png":
            write_png(path, rendered.image, exposure, channels=rendered.channels)
        else:
            write_jpeg(path, rendered.image, exposure, channels=rendered.channels)


# -- command line -------------------------------------------------------------------------

def add_arguments(p):
    p.add_argument("scene", help="scene XML file")
    p.add_argument("-o", "--output", metavar="FILE",
                   help="output image; its extension picks the format: none = FILE.exr + "
                        "FILE.png, .exr = EXR alone, .png or .jpg = that image and the EXR "
                        "beside it (default: the scene's name, EXR + PNG, in the current "
                        "directory)")
    p.add_argument("-m", "--mode", "--variant", dest="variant", default="llvm_ad_rgb",
                   metavar="VARIANT", help="Mitsuba variant (default: %(default)s)")
    p.add_argument("-t", "--threads", type=positive_int, metavar="COUNT",
                   help="render with this many threads (default: all cores)")
    p.add_argument("-s", "--sensor", type=nonnegative_int, default=0, metavar="INDEX",
                   help="index of the sensor, in the scene's order (default: 0)")
    p.add_argument("-D", "--define", dest="defines", type=define, action="append", default=[],
                   metavar="KEY=VALUE", help="set the scene's parameter $KEY (repeatable)")
    p.add_argument("-a", dest="paths", action="append", default=[], metavar="PATH1;PATH2",
                   help="add folders to the search path of files the scene loads")
    p.add_argument("--spp", type=positive_int, metavar="N",
                   help="samples per pixel (default: the scene's sampler; samplers such as "
                        "stratified round it up as Mitsuba does)")
    p.add_argument("--seed", type=uint32, default=0,
                   help="seed of the samples, 0..2^32-1 (default: 0; the same seed gives "
                        "the same image)")
    p.add_argument("--exposure", type=finite_float, default=0.0, metavar="STOPS",
                   help="scale the PNG/JPEG by 2^STOPS before tone mapping (the EXR is "
                        "never scaled; default: 0)")
    p.add_argument("--no-exr", action="store_true",
                   help="write the PNG/JPEG alone, without the EXR")
    p.add_argument("--pass-samples", type=positive_int, default=DEFAULT_PASS_SAMPLES,
                   metavar="N", help="samples (pixels x spp) traced at once; bounds memory "
                                     "(default: %(default)s)")
    loud = p.add_mutually_exclusive_group()
    loud.add_argument("-q", "--quiet", action="store_true",
                      help="no progress bar and no summary, only errors")
    loud.add_argument("-v", "--verbose", action="count", default=0,
                      help="Mitsuba's log messages (-v: info, -vv: debug)")


def _check_scene_file(scene_path):
    if not os.path.exists(scene_path):
        raise UsageError(f"scene {scene_path}: no such file")
    if os.path.isdir(scene_path):
        raise UsageError(f"scene {scene_path}: is a folder, not a scene file")


def _check_loaded(scene, scene_path, sensor, spp):
    n = len(scene.sensors())
    if n == 0:
        raise UsageError(f"{scene_path}: the scene has no <sensor> to render from")
    if sensor >= n:
        raise UsageError(f"-s {sensor}: the scene has {n} sensor(s): indices 0..{n - 1}")
    if not spp and scene_spp(scene, sensor) < 1:
        raise UsageError(f"{scene_path}: the sampler takes {scene_spp(scene, sensor)} samples "
                         f"per pixel; give at least 1 (--spp N, or the scene's -D parameter)")


@contextlib.contextmanager
def _threads(count):
    """Render with ``count`` threads (None: all cores), as Mitsuba's ``-t``. Only the render:
    Mitsuba's EXR reader and writer hang with a thread pool of one."""
    import drjit as dr
    before = dr.thread_count()
    if count:
        dr.set_thread_count(count)
    try:
        yield
    finally:
        dr.set_thread_count(before)


def run(args):
    import mitsuba as mi

    t0 = time.perf_counter()
    scene_path = args.scene
    # everything that can be refused is refused before the scene is loaded ...
    paths = [p for a in args.paths for p in a.split(";") if p]
    for p in paths:
        if not os.path.isdir(p):
            raise UsageError(f"-a {p}: no such folder")
    _check_scene_file(scene_path)
    inputs = scene_inputs(scene_path, paths)
    if args.output:
        check_not_input(args.output, scene_path, inputs)
    outputs = plan_outputs(scene_path, args.output, exr=not args.no_exr)
    check_outputs(outputs, scene_path, inputs)
    set_variant(args.variant)
    mi.set_log_level([mi.LogLevel.Error if args.quiet else mi.LogLevel.Warn,
                      mi.LogLevel.Info, mi.LogLevel.Debug][min(args.verbose, 2)])
    resolver = mi.file_resolver()
    for p in map(os.path.abspath, paths):
        if p not in map(str, resolver):
            resolver.append(p)
    # ... or, when it takes the scene to know, before rendering
    scene = load_scene(scene_path, dict(args.defines))
    _check_loaded(scene, scene_path, args.sensor, args.spp)
    load_seconds = time.perf_counter() - t0
    with _threads(args.threads):
        r = render_image(scene, args.spp, args.pass_samples, args.seed, args.sensor,
                         label=os.path.basename(scene_path), progress=not args.quiet,
                         measure_compile=True)
    del scene
    requested = args.spp
    if requested and r.spp != requested and not args.quiet:
        print(f"note: the scene's sampler rounds --spp {requested} up: {r.spp} spp rendered "
              f"(as Mitsuba does)", file=sys.stderr)
    t1 = time.perf_counter()
    _write_outputs(r, outputs, args.exposure)
    if not args.quiet:
        t2 = time.perf_counter()
        print(f"wrote {' and '.join(p for p, _ in outputs)}: {r.spp} spp in {r.passes} "
              f"pass(es); {t2 - t0:.2f} s in all = {load_seconds:.2f} s loading + "
              f"{r.compile_seconds:.2f} s compiling + "
              f"{r.seconds - r.compile_seconds:.2f} s rendering + {t2 - t1:.2f} s writing")
    return 0
