"""Setting Mitsuba up for a command: the variant, a user's plugin files, scenes.

``set_variant`` is the one way the commands activate a variant: it checks that the variant
can run here (``check_variant``), activates it and registers this package's plugins in it.
``run_file`` runs a user's Python file (``--load FILE.py``), which registers its own plugins
once the variant is set.
"""
import os
import re
import runpy
import sys

from .arguments import UsageError
from .messages import last_line, note_registered, suggest
from .paths import copied_example, installed_copy

__all__ = ["check_variant", "set_variant", "run_file", "check_file", "load_scene",
           "shapes_without_bsdf", "check_scene", "find_input", "scene_spp"]

#: Mitsuba's variant names: backend, AD, colour, polarization, precision
_VARIANT = re.compile(r"(scalar|llvm|cuda|metal)(_ad)?_(rgb|mono|spectral)(_polarized)?(_double)?$")


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
        raise UsageError(f"{what}{suggest(variant, built)} (it has {', '.join(built)})")
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
    from .core.plugin import register
    register()


#: the inputs already said to come from the installed copy (said once per command)
_NOTED = set()


def find_input(path, what="scene", quiet=False):
    """``path``, or when it names no file here: the example file that the ``examples``
    command copied into ``examples/`` here (``paths.copied_example``: the user's copy, which
    they may have edited), else a scene or example installed with the package
    (``paths.installed_copy``: ``scenes/as_sphere.xml`` run from any folder); which one is
    said once on stderr (unless ``quiet``)."""
    copy = copied_example(path)
    whose = "the copy the examples command made here"
    if copy is None:
        copy, whose = installed_copy(path), "the one that comes with mitsuba_brdfs"
    if copy is None:
        return path
    if not quiet and copy not in _NOTED:
        _NOTED.add(copy)
        print(f"note: {what} {path} is not in this folder; using {whose}, {copy}",
              file=sys.stderr)
    return copy


def run_file(path):
    """Run a user's Python file (``--load FILE.py``: it registers its plugins with
    ``mi.register_bsdf``), once the variant is set; a name that is no file here may be an
    installed example (``find_input``). A missing file is a ``FileNotFoundError``, a file
    that fails a ``ValueError`` naming it and the cause."""
    path = find_input(path, "--load")
    if os.path.isdir(path):
        raise UsageError(f"--load {path}: is a folder, not a Python file")
    if not os.path.isfile(path):
        raise FileNotFoundError(f"--load {path}: no such file")
    check_file(path, "--load")  # empty: it would register nothing
    note_registered(path)
    try:
        runpy.run_path(path, run_name="__mitsuba_brdfs_load__")
    except (Exception, SystemExit) as e:
        raise ValueError(f"--load {path}: {type(e).__name__}: {last_line(e)}") from None


def check_file(path, what="scene"):
    """Refuse (``UsageError``, one line) a path that is not a file with something in it:
    missing, a folder, or empty (Mitsuba's parser says "No document element found")."""
    path = os.fspath(path)
    name = f"{what} {path}" if what else path
    if os.path.isdir(path):
        raise UsageError(f"{name}: is a folder, not a file")
    if not os.path.exists(path):
        raise UsageError(f"{name}: no such file")
    with open(path, "rb") as f:
        if not f.read(1 << 16).strip():
            raise UsageError(f"{name}: the file is empty")


def load_scene(path, defines=None):
    """``mi.load_file`` with ``<default>`` overrides (strings, as ``-D key=value`` gives)."""
    import mitsuba as mi
    return mi.load_file(str(path), **{k: str(v) for k, v in (defines or {}).items()})


def shapes_without_bsdf(path, defines=None):
    """The shapes of a scene file that have no BSDF (Mitsuba gives each a default grey
    diffuse), as "sphere (scene.xml, line 3)"; shapes that emit light (area lights, whose
    default is black) and instances are left out. Read with Mitsuba's own parser, so
    ``<include>`` files and ``$`` parameters are resolved; [] for a file it cannot parse
    (loading it says why)."""
    import mitsuba as mi
    defines = {k: str(v) for k, v in (defines or {}).items()}
    try:
        state = mi.parser.parse_file(mi.parser.ParserConfig(mi.variant()), os.fspath(path),
                                     **defines)
    except Exception:  # noqa: BLE001  (loading the scene reports it)
        return []
    nodes, ids = state.nodes, dict(state.id_to_index)

    def children(node):
        props, out = node.props, []
        for key in props.keys():
            value = props[key]
            if isinstance(value, mi.Properties.ResolvedReference):
                out.append(nodes[value.index()].type)
            elif isinstance(value, mi.Properties.Reference):
                out.append(nodes[ids[value.id()]].type if value.id() in ids else None)
        return out

    missing = []
    for node in nodes:
        if node.type != mi.ObjectType.Shape:
            continue
        kinds = children(node)
        if node.props.plugin_name() in ("instance", "shapegroup") or None in kinds \
                or mi.ObjectType.BSDF in kinds or mi.ObjectType.Emitter in kinds:
            continue
        name = str(state.files[node.file_index])
        try:
            with open(name, "rb") as f:
                line = f.read(node.offset).count(b"\n") + 1
            where = f"{os.path.basename(name)}, line {line}"
        except OSError:
            where = os.path.basename(name)
        label = node.props.plugin_name() + (f" '{node.props.id()}'" if node.props.id() else "")
        missing.append(f"{label} ({where})")
    return missing


def check_scene(scene, path, defines=None, render=True):
    """Refuse (``UsageError``, one line) a loaded scene with what Mitsuba users get wrong:
    a shape without a BSDF (``shapes_without_bsdf``: Mitsuba would silently give it a grey
    diffuse); with ``render``, also a scene without an ``<integrator>`` or a ``<sensor>``
    (``mitsuba`` refuses both), and without any emitter (every pixel black), unless its
    integrator needs no light (``aov``, ``depth``)."""
    missing = shapes_without_bsdf(path, defines)
    if missing:
        more = f" and {len(missing) - 1} more" if len(missing) > 1 else ""
        raise UsageError(f"{path}: the shape {missing[0]}{more} has no <bsdf>, and Mitsuba "
                         f"would give it a grey diffuse; give it one (<bsdf type=\"diffuse\"/> "
                         f"keeps that default)")
    if not render:
        return
    if scene.integrator() is None:
        raise UsageError(f"{path}: the scene has no <integrator>, which Mitsuba's mitsuba "
                         f"command refuses too; add one, e.g. <integrator type=\"path\"/>")
    if not scene.sensors():
        raise UsageError(f"{path}: the scene has no <sensor> to render from")
    lightless = scene.integrator().class_name() in ("AOVIntegrator", "DepthIntegrator")
    if not scene.emitters() and not lightless:
        raise UsageError(f"{path}: the scene has no <emitter> (nor an area light): every "
                         f"pixel would be black; add one, e.g. <emitter type=\"constant\"/>")


def scene_spp(scene, sensor=0):
    """The samples per pixel of the sensor's sampler."""
    return scene.sensors()[sensor].sampler().sample_count()
