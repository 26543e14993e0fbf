"""The ``render`` command: a scene rendered in passes (``passes.render_image``) and written
whole (``output``).

The command (Mitsuba's C++ ``mitsuba`` executable cannot load Python plugins;
its options are kept where they exist: ``-m``, ``-t``, ``-s``, ``-D``, ``-a``, ``-o``,
``-v``)::

    python -m mitsuba_brdfs render mitsuba_brdfs/scenes/as_sphere.xml -o as_sphere --spp 64

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
import contextlib
import os
import sys
import time

from .arguments import UsageError, define, finite_float, nonnegative_int, positive_int, uint32
from .output import check_folder, write_exr, write_jpeg, write_png
from .passes import DEFAULT_PASS_SAMPLES, render_image
from .variant import load_scene, scene_spp, set_variant

__all__ = ["WRITES_ATOMICALLY", "plan_outputs", "check_not_input", "check_outputs",
           "scene_inputs", "add_arguments", "run"]

#: every file of this command goes through ``output.atomic``: an interruption can say what
#: was written
WRITES_ATOMICALLY = True


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
