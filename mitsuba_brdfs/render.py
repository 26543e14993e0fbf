"""The ``render`` command: scenes rendered in passes (``passes.render_image``) and written
whole (``output``).

Mitsuba's C++ ``mitsuba`` executable cannot load Python plugins; this command renders as it
does, with its options where they exist (``-m``, ``-t``, ``-s``, ``-D``, ``-a``, ``-o``,
``-v``, ``-O``, ``-S``, ``-W``, several scenes per call) and ``--load FILE.py`` for a
user's own plugins::

    python -m mitsuba_brdfs render scenes/as_sphere.xml -o as_sphere --spp 64

What it writes, by the extension of ``-o`` (default: the scene's name, in the current
directory; with several scenes, ``-o`` names a folder and each scene keeps its name):

- no extension: the film as Mitsuba writes it (``NAME.exr``, or ``NAME.pfm`` /
  ``NAME.rgbe`` by the film's ``file_format``; every channel, its names, pixel format and
  ``component_format``: float16 by default) and ``NAME.png`` (the colour, tone-mapped to
  8-bit sRGB);
- ``.exr``, ``.pfm``, ``.rgbe`` / ``.hdr``: that HDR image alone;
- ``.png``, ``.jpg``: that image, and the film's HDR image beside it unless ``--no-exr``,
  so the HDR image is never dropped without being asked.

Everything that can be checked is checked before rendering: the outputs' formats and
folders, that no output is the scene or a file it loads, nor a read-only or immutable
file, the variant, the scene, its sensor and sample count, and the memory the render needs
(``passes.memory_estimate``; ``--max-memory`` overrides the limit). A stop (Ctrl-C,
SIGTERM) writes the passes finished so far and says how many samples they hold.
"""
import contextlib
import os
import re
import sys
import time

from .arguments import (UsageError, add_load, define, finite_float, int_range, nonnegative_int,
                        positive_int, refuse_repeated, uint32)
from .messages import one_line
from .output import check_folder, check_target, write_exr, write_hdr, write_jpeg, write_png
from .passes import (DEFAULT_PASS_SAMPLES, Interrupted, memory_estimate, memory_limit,
                     render_image)
from .variant import (check_file, check_scene, find_input, load_scene, run_file, scene_spp,
                      set_variant)

__all__ = ["WRITES_ATOMICALLY", "film_formats", "plan_outputs", "check_not_input",
           "check_outputs", "check_memory", "scene_inputs", "add_arguments", "run"]

#: every file of this command goes through ``output.atomic``: an interruption can say what
#: was written
WRITES_ATOMICALLY = True

_GB = 1e9


# -- outputs ------------------------------------------------------------------------------

#: extension -> format; the HDR formats are those of Mitsuba's hdrfilm
_FORMATS = {".exr": "exr", ".pfm": "pfm", ".rgbe": "rgbe", ".hdr": "rgbe", ".png": "png",
            ".jpg": "jpeg", ".jpeg": "jpeg"}
_HDR = {"exr": ".exr", "pfm": ".pfm", "rgbe": ".rgbe"}


def film_formats(film):
    """(file format, component format) of a film as Mitsuba's ``hdrfilm`` writes it:
    ``exr``, ``pfm`` or ``rgbe``, and ``float16``, ``float32`` or ``uint32`` (read from its
    description; a film without them: ``exr``, ``float32``)."""
    text = str(film)
    fmt = re.search(r"file_format = (\w+)", text)
    comp = re.search(r"component_format = (\w+)", text)
    kind = {"openexr": "exr", "pfm": "pfm", "rgbe": "rgbe"}.get(
        fmt.group(1).lower() if fmt else "", "exr")
    comp = comp.group(1).lower() if comp else "float32"
    return kind, comp if comp in ("float16", "float32", "uint32") else "float32"


def plan_outputs(scene_path, output=None, exr=True, film_format="exr"):
    """The files ``render`` writes, as [(path, format)] with format exr, pfm, rgbe, png or
    jpeg (the rule of the module's docstring); ``film_format`` is the film's HDR format."""
    if output is None:
        output = os.path.splitext(os.path.basename(os.fspath(scene_path)))[0]
    output = os.fspath(output)
    if output.endswith(("/", os.sep)) or os.path.isdir(output):
        raise UsageError(f"-o {output}: is a folder; name the image, e.g. "
                         f"{os.path.join(output, 'image.exr')}")
    stem, ext = os.path.splitext(output)
    kind = _FORMATS.get(ext.lower())
    if ext and kind is None:
        raise UsageError(f"-o {output}: cannot write {ext!r} images; use .exr, .pfm, .rgbe, "
                         f".hdr, .png, .jpg or no extension (the film's format + PNG)")
    hdr = (stem if ext else output) + _HDR[film_format]
    if not ext:
        plan = [(hdr, film_format), (output + ".png", "png")]
    elif kind in _HDR:
        plan = [(output, kind)]
    else:
        plan = [(hdr, film_format), (output, kind)]
    if not exr:
        if kind in _HDR:
            raise UsageError(f"--no-exr with -o {output}: nothing would be written")
        plan = [p for p in plan if p[1] not in _HDR]
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
    """Refuse (``UsageError``) an output that is an input, a folder, a file that may not be
    replaced (read-only, immutable), or in a folder that cannot be created or written."""
    for path, _ in outputs:
        check_not_input(path, scene_path, inputs)
        if os.path.isdir(path):
            raise UsageError(f"-o {path}: is a folder; name the image")
        check_folder(os.path.dirname(os.path.abspath(path)), f"cannot write {path}")
        check_target(path, f"-o {path}")


def check_memory(scene, scene_path, args):
    """Refuse (``UsageError``) a render that needs more memory than ``--max-memory`` GB (by
    default ``passes.memory_limit()``), or a film larger than Dr.Jit's arrays hold."""
    need, per_pass, block = memory_estimate(scene, args.spp, args.pass_samples, args.sensor,
                                            args.wavefront)
    w, h = scene.sensors()[args.sensor].film().crop_size()
    if w * h * block > 2 ** 32 - 1:
        raise UsageError(f"{scene_path}: a film of {w} x {h} pixels x {block} channels holds "
                         f"{w * h * block:.3g} values, more than Dr.Jit's arrays can "
                         f"(2^32); render it in tiles (crop windows) instead")
    limit = args.max_memory * _GB if args.max_memory else memory_limit()
    if need > limit:
        how = ("" if args.max_memory else
               " (3/4 of this machine's memory)")
        raise UsageError(f"{scene_path}: a {w} x {h} render needs about {need / _GB:.1f} GB "
                         f"of memory (film, passes of {per_pass:.3g} samples, writing), over "
                         f"the limit of {limit / _GB:.1f} GB{how}; lower the resolution, "
                         f"or raise the limit with --max-memory GB")


def _write_outputs(rendered, outputs, exposure, component_format):
    for path, kind in outputs:
        if kind == "exr":
            write_exr(path, rendered.image, rendered.channels, component_format)
        elif kind in ("pfm", "rgbe"):
            write_hdr(path, rendered.image, rendered.channels, kind)
        elif kind == "png":
            write_png(path, rendered.image, exposure, channels=rendered.channels)
        else:
            write_jpeg(path, rendered.image, exposure, channels=rendered.channels)


# -- command line -------------------------------------------------------------------------

def add_arguments(p):
    p.add_argument("scenes", nargs="+", metavar="SCENE",
                   help="scene XML file(s), rendered one after the other")
    p.add_argument("-o", "--output", metavar="FILE",
                   help="output image; its extension picks the format: none = the film's "
                        "HDR image (FILE.exr, or .pfm/.rgbe by its file_format) + FILE.png, "
                        ".exr/.pfm/.rgbe/.hdr = that image alone, .png or .jpg = that image "
                        "and the HDR image beside it (default: the scene's name, in the "
                        "current directory). With several scenes: a folder")
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
    add_load(p)
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
                   help="write the PNG/JPEG alone, without the film's HDR image")
    p.add_argument("--pass-samples", type=positive_int, default=DEFAULT_PASS_SAMPLES,
                   metavar="N", help="samples (pixels x spp) traced at once; bounds memory "
                                     "(default: %(default)s)")
    p.add_argument("--max-memory", type=_positive_float, metavar="GB",
                   help="refuse a render estimated to need more memory than this (default: "
                        "3/4 of the machine's memory)")
    jit = p.add_argument_group("JIT options (llvm_* and cuda_* variants), as Mitsuba's")
    jit.add_argument("-O", dest="optimize", type=int_range(0, 5), default=5, metavar="[0-5]",
                     help="optimizations: 1 de-duplicate functions, 2 and constant "
                          "propagation, 3 and value numbering, 4 and call optimizations, 5 "
                          "and loop optimizations (default: 5; 0, none, crashes Mitsuba)")
    jit.add_argument("-S", dest="print_ir", action="store_true",
                     help="print the LLVM or PTX intermediate representation of the kernels")
    jit.add_argument("-W", dest="wavefront", action="count", default=0,
                     help="render in wavefronts instead of one megakernel (-WW: calls too); "
                          "needs more memory")
    loud = p.add_mutually_exclusive_group()
    loud.add_argument("-q", "--quiet", action="store_true",
                      help="no progress bar and no summary, only errors")
    loud.add_argument("-v", "--verbose", action="count", default=0,
                      help="Mitsuba's log messages (-v: info, -vv: debug)")


def _positive_float(text):
    x = finite_float(text)
    if x <= 0:
        import argparse
        raise argparse.ArgumentTypeError(f"must be > 0, got {text!r}")
    return x


def _check_loaded(scene, scene_path, sensor, spp):
    n = len(scene.sensors())
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


def _jit_flags(args):
    """Dr.Jit's flags for ``-O``, ``-S`` and ``-W``, as Mitsuba's ``mitsuba`` sets them, for
    the time of the command."""
    import drjit as dr
    f = dr.JitFlag
    flags = [(f.MergeFunctions, args.optimize >= 1), (f.ConstantPropagation, args.optimize >= 2),
             (f.ValueNumbering, args.optimize >= 3), (f.OptimizeCalls, args.optimize >= 4),
             (f.OptimizeLoops, args.optimize >= 5)]
    if args.print_ir:
        flags.append((f.PrintIR, True))
    if args.wavefront:
        flags.append((f.SymbolicLoops, False))
    if args.wavefront > 1:
        flags.append((f.SymbolicCalls, False))
    stack = contextlib.ExitStack()
    for flag, value in flags:
        if dr.flag(flag) != value:
            stack.enter_context(dr.scoped_set_flag(flag, value))
    return stack


def _plans(args, inputs):
    """Each scene's output name (its ``-o``) and files, checked; several scenes write into
    the folder ``-o`` names, each under its own name."""
    names = {}
    for scene_path in args.scenes:
        out = args.output
        if len(args.scenes) > 1:
            stem = os.path.splitext(os.path.basename(scene_path))[0]
            out = os.path.join(args.output, stem) if args.output else stem
        elif out:
            check_not_input(out, scene_path, inputs[scene_path])
        outputs = plan_outputs(scene_path, out, exr=not args.no_exr)
        check_outputs(outputs, scene_path, inputs[scene_path])
        if out in names.values():
            raise UsageError(f"{scene_path}: two scenes named {os.path.basename(out)!r} would "
                             f"write the same files; render them one at a time")
        names[scene_path] = out
    return names


def run(args):
    import mitsuba as mi

    t0 = time.perf_counter()
    # a scene named as the README does (scenes/as_sphere.xml) from another folder: the copy
    # installed with the package
    args.scenes = [find_input(s, "scene", args.quiet) for s in args.scenes]
    # everything that can be refused is refused before a scene is loaded ...
    paths = [p for a in args.paths for p in a.split(";") if p]
    for p in paths:
        if not os.path.isdir(p):
            raise UsageError(f"-a {p}: " + ("is a file, not a folder" if os.path.exists(p)
                                            else "no such folder"))
    for scene_path in args.scenes:
        check_file(scene_path)
    args.defines = list(refuse_repeated(args.defines, "-D").items())  # -D a=1 -D a=2
    if args.optimize == 0:
        raise UsageError("-O 0: rendering with Dr.Jit's function merging switched off crashes "
                         "this Mitsuba (3.9.1 with Dr.Jit 1.5; its own `mitsuba -O 0` too); "
                         "use -O 1 to -O 5")
    several = len(args.scenes) > 1 and args.output
    if several and (os.path.splitext(args.output)[1] or os.path.isfile(args.output)):
        raise UsageError(f"-o {args.output}: with several scenes, -o names a folder (each "
                         f"scene is written there under its own name)")
    inputs = {s: scene_inputs(s, paths) for s in args.scenes}
    names = _plans(args, inputs)
    set_variant(args.variant)
    mi.set_log_level([mi.LogLevel.Error if args.quiet else mi.LogLevel.Warn,
                      mi.LogLevel.Info, mi.LogLevel.Debug][min(args.verbose, 2)])
    resolver = mi.file_resolver()
    for p in map(os.path.abspath, paths):
        if p not in map(str, resolver):
            resolver.append(p)
    for path in args.load:
        run_file(path)
    with _jit_flags(args):
        for scene_path in args.scenes:
            _render_one(args, scene_path, names[scene_path], inputs[scene_path], t0)
            t0 = time.perf_counter()
    return 0


def _render_one(args, scene_path, out, inputs, t0):
    # ... or, when it takes the scene to know, before rendering
    try:
        scene = load_scene(scene_path, dict(args.defines))
    except Exception as e:  # said with the scene's name, when Mitsuba's message lacks it
        text = one_line(str(e))
        if os.path.basename(scene_path) in text or "KeyboardInterrupt" in text:
            raise
        raise UsageError(f"{scene_path}: {text}") from None
    check_scene(scene, scene_path, dict(args.defines))
    _check_loaded(scene, scene_path, args.sensor, args.spp)
    file_format, component_format = film_formats(scene.sensors()[args.sensor].film())
    outputs = plan_outputs(scene_path, out, not args.no_exr, file_format)
    check_outputs(outputs, scene_path, inputs)
    check_memory(scene, scene_path, args)
    load_seconds = time.perf_counter() - t0
    try:
        with _threads(args.threads):
            r = render_image(scene, args.spp, args.pass_samples, args.seed, args.sensor,
                             label=os.path.basename(scene_path), progress=not args.quiet,
                             measure_compile=True)
    except Interrupted as stop:
        if stop.rendered is not None:  # keep what was rendered
            r = stop.rendered
            print(f"\nstopped after {r.passes} pass(es): writing the {r.spp} spp they hold",
                  file=sys.stderr)
            _write_outputs(r, outputs, args.exposure, component_format)
        raise
    del scene
    requested = args.spp
    if requested and r.spp != requested and not args.quiet:
        print(f"note: the scene's sampler rounds --spp {requested} up: {r.spp} spp rendered "
              f"(as Mitsuba does)", file=sys.stderr)
    t1 = time.perf_counter()
    _write_outputs(r, outputs, args.exposure, component_format)
    if not args.quiet:
        t2 = time.perf_counter()
        print(f"wrote {' and '.join(p for p, _ in outputs)}: {r.spp} spp in {r.passes} "
              f"pass(es); {t2 - t0:.2f} s in all = {load_seconds:.2f} s loading + "
              f"{r.compile_seconds:.2f} s compiling + "
              f"{r.seconds - r.compile_seconds:.2f} s rendering + {t2 - t1:.2f} s writing")
