"""Rendering scenes in passes and writing images whole.

Mitsuba renders all samples of a call at once, so the memory of a call can grow with
width x height x spp (how much depends on the integrator; ``docs/performance.md``
measures it). ``render_passes`` splits the samples
into passes of bounded size and averages them (each pass weighted by its sample count),
showing progress. ``write_exr`` / ``write_png`` write
to a temporary file beside the target and rename it, so an interrupted command never
leaves a half-written image.

Command line (Mitsuba's C++ ``mitsuba`` executable cannot load Python plugins)::

    python -m mitsuba_brdfs render mitsuba_brdfs/scenes/as_sphere.xml -o renders/as_sphere.exr \
        --spp 64
"""
import contextlib
import math
import os
import sys
import tempfile
import time

import numpy as np

__all__ = ["DEFAULT_PASS_SAMPLES", "progress_bar", "advance", "render_passes", "render_file", "load_scene",
           "write_exr", "read_exr", "write_png", "tonemap", "add_arguments", "run"]

#: samples (pixels x spp) traced at once; bounds the memory of one pass (~1-2 GiB)
DEFAULT_PASS_SAMPLES = 1 << 22


def set_variant(variant):
    """Activate ``variant`` (and register the plugins in it)."""
    import mitsuba as mi
    if mi.variant() != variant:
        mi.set_variant(variant)
    import mitsuba_brdfs
    mitsuba_brdfs.register()


def load_scene(path, defines=None):
    """``mi.load_file`` with ``<default>`` overrides (strings, as ``-D key=value`` gives)."""
    import mitsuba as mi
    return mi.load_file(str(path), **{k: str(v) for k, v in (defines or {}).items()})


def scene_spp(scene, sensor=0):
    return scene.sensors()[sensor].sampler().sample_count()


def pass_sizes(spp, pixels, pass_samples=DEFAULT_PASS_SAMPLES):
    """Split ``spp`` into passes of at most ``pass_samples`` samples (>= 1 spp each)."""
    per = max(1, min(spp, pass_samples // max(pixels, 1)))
    n = math.ceil(spp / per)
    base, extra = divmod(spp, n)  # balanced: passes differ by at most one spp
    return [base + (i < extra) for i in range(n)]


def progress_bar(total, label, unit="it", enabled=True):
    """A tqdm progress bar on stderr. Where stderr is not a terminal (a CI log) it is
    redrawn at most every 5 seconds, so logs stay short."""
    from tqdm import tqdm
    return tqdm(total=total, desc=label, unit=unit, file=sys.stderr, disable=not enabled,
                mininterval=0.1 if sys.stderr.isatty() else 5.0, dynamic_ncols=True)


def advance(bar, n=1, note=""):
    """Count ``n`` more steps done on ``bar`` (a ``progress_bar``, or None) and show ``note``
    beside it."""
    if bar is not None:
        bar.set_postfix_str(note, refresh=False)
        bar.update(n)


def render_passes(scene, spp=None, pass_samples=DEFAULT_PASS_SAMPLES, seed=0, sensor=0,
                  label="render", progress=True, integrator=None):
    """Render ``scene`` with ``spp`` samples per pixel in bounded passes.

    Returns (image as float32 numpy array (H, W, C), seconds). Pass ``i`` uses seed
    ``seed * 65536 + i``, so passes are independent and the result reproducible.
    """
    import drjit as dr
    import mitsuba as mi

    spp = spp or scene_spp(scene, sensor)
    film = scene.sensors()[sensor].film()
    w, h = film.crop_size()
    sizes = pass_sizes(spp, w * h, pass_samples)
    acc = None
    t0 = time.perf_counter()
    with progress_bar(spp, label, "spp", enabled=progress) as bar:
        for i, n in enumerate(sizes):
            img = mi.render(scene, spp=n, seed=seed * 65536 + i, sensor=sensor,
                            integrator=integrator)
            arr = np.array(img, dtype=np.float64)
            acc = arr * n if acc is None else acc + arr * n
            del img
            dr.flush_malloc_cache()
            advance(bar, n, f"pass {i + 1}/{len(sizes)}")
    seconds = time.perf_counter() - t0
    return (acc / spp).astype(np.float32), seconds


def _channel_names(c):
    return {1: ["Y"], 3: ["R", "G", "B"], 4: ["R", "G", "B", "A"]}.get(
        c, [f"C{i}" for i in range(c)])


@contextlib.contextmanager
def _atomic(path):
    """Yield a temporary path in the target's directory; rename it over ``path`` on success."""
    path = os.fspath(path)
    directory = os.path.dirname(os.path.abspath(path))
    os.makedirs(directory, exist_ok=True)
    suffix = os.path.splitext(path)[1]
    fd, tmp = tempfile.mkstemp(prefix=".partial-", suffix=suffix, dir=directory)
    os.close(fd)
    try:
        yield tmp
        # mkstemp creates the file readable by its owner only: give it the mode of any
        # new file (0o666 less the umask)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def write_exr(path, image):
    """Write a float32 (H, W, C) image as a ZIP-compressed OpenEXR file, atomically."""
    import OpenEXR
    img = np.ascontiguousarray(np.asarray(image, dtype=np.float32))
    if img.ndim == 2:
        img = img[..., None]
    names = _channel_names(img.shape[2])
    channels = {n: np.ascontiguousarray(img[..., i]) for i, n in enumerate(names)}
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with _atomic(path) as tmp:
        with OpenEXR.File(header, channels) as f:
            f.write(tmp)


def read_exr(path):
    """Read an OpenEXR file written by ``write_exr`` as float32 (H, W, C)."""
    import OpenEXR
    with OpenEXR.File(os.fspath(path), separate_channels=True) as f:
        chans = {k: v.pixels for k, v in f.channels().items()}
    for names in (["R", "G", "B", "A"], ["R", "G", "B"], ["Y"]):
        if set(names) <= set(chans) and len(chans) == len(names):
            break
    else:
        names = sorted(chans)
    return np.stack([np.asarray(chans[n], dtype=np.float32) for n in names], axis=-1)


def tonemap(image, exposure=0.0):
    """Linear RGB -> 8-bit sRGB (clamped), as an (H, W, 3) uint8 array."""
    x = np.asarray(image, dtype=np.float64)[..., :3] * 2.0 ** exposure
    x = np.clip(np.nan_to_num(x, nan=0.0, posinf=1.0), 0.0, 1.0)
    srgb = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.round(srgb * 255).astype(np.uint8)


def write_png(path, image, exposure=0.0, already_tonemapped=False):
    """Write an sRGB PNG (tone-mapped from linear unless ``already_tonemapped``), atomically."""
    import mitsuba as mi
    rgb = np.array(image if already_tonemapped else tonemap(image, exposure), dtype=np.uint8, order="C")
    bmp = mi.Bitmap(rgb, pixel_format=mi.Bitmap.PixelFormat.RGB)
    with _atomic(path) as tmp:
        bmp.write(tmp, mi.Bitmap.FileFormat.PNG)


def render_file(scene_path, out=None, spp=None, variant="llvm_ad_rgb", defines=None,
                pass_samples=DEFAULT_PASS_SAMPLES, seed=0, progress=True):
    """Load, render and write ``scene_path``: returns (exr path, png path, seconds)."""
    set_variant(variant)
    scene = load_scene(scene_path, defines)
    out = out or os.path.splitext(os.path.basename(str(scene_path)))[0] + ".exr"
    image, seconds = render_passes(scene, spp, pass_samples, seed,
                                   label=os.path.basename(str(scene_path)), progress=progress)
    png = os.path.splitext(out)[0] + ".png"
    write_exr(out, image)
    write_png(png, image)
    return out, png, seconds


# -- command line -----------------------------------------------------------------------

def parse_define(text):
    key, sep, value = text.partition("=")
    if not sep or not key:
        raise ValueError(f"-D expects key=value, got {text!r}")
    return key.strip(), value.strip()


def add_arguments(p):
    p.add_argument("scene", help="scene XML file")
    p.add_argument("-o", "--output", help="output EXR (default: <scene name>.exr); "
                   "a tone-mapped sRGB PNG is written beside it")
    p.add_argument("--spp", type=int, help="samples per pixel (default: the scene's sampler)")
    p.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant (default: llvm_ad_rgb)")
    p.add_argument("-D", dest="defines", action="append", default=[], metavar="KEY=VALUE",
                   help="override a <default> of the scene (repeatable)")
    p.add_argument("--pass-samples", type=int, default=DEFAULT_PASS_SAMPLES,
                   help="samples traced per pass, bounds memory (default: %(default)s)")
    p.add_argument("--seed", type=int, default=0)


def run(args):
    defines = dict(parse_define(d) for d in args.defines)
    if args.spp is not None and args.spp < 1:
        raise ValueError("--spp must be >= 1")
    exr, png, seconds = render_file(args.scene, args.output, args.spp, args.variant, defines,
                                    args.pass_samples, args.seed)
    print(f"wrote {exr} and {png} ({seconds:.1f} s)")
    return 0
